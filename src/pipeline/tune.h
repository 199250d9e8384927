// tune.h: `hbil tune`: a preset for the user's shot, from its references. A coordinate
// search, not a grid: starting from the base configuration, each key of the search in turn
// is set to each of its candidate values with the others held, and the best value is kept;
// passes repeat until one changes nothing (at most `max_passes`). Each configuration is
// measured as `hbil bench` measures it (the errors of every referenced layer, the time per
// frame as `hbil run --no-display`), and measured once; with a budget, a configuration whose
// one timed run lands within `retime_band` of the budget is timed three more times and its
// median kept, so that one slow or fast run does not decide whether it fits.
//
// The objective is the PSNR of one layer. With a budget, the most accurate configuration
// whose time per frame is within it; without one, the cheapest whose PSNR is within
// `tolerance_db` of the best found (a second search from the best, over the same keys,
// towards lower time).
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/bench.h"

namespace hbil::pipeline {

// One key of the search and its candidates, as --set values ("auto" allowed where the key
// takes it).
struct TuneAxis {
  std::string key;
  std::vector<std::string> values;
};

// method, slices, steps, gather_steps, gather_radius, thickness, gather_thickness, with the
// values a user would try (gather_radius and thickness: "auto" and numbers around the auto
// values of the shot, 1/2 and 2 times).
std::vector<TuneAxis> default_tune_axes(const Params& resolved_base);

struct TuneSettings {
  BenchSettings bench;  // shot, frames, refs, mask; configs: the base (first only)
  std::string layer;    // the objective ("" = composite when referenced, else the first)
  double budget = 0;    // seconds per frame; 0 = none
  double tolerance_db = 0.1;
  int max_passes = 3;
  double retime_band = 0.2;       // fraction of the budget either side of it (0: never retime)
  std::vector<std::string> keys;  // the keys searched, of default_tune_axes ("": all)
};

struct TuneStep {
  std::string change;                      // "slices=4", or "base"
  double psnr = 0, seconds_per_frame = 0;  // ConfigResult::cost_per_frame (calibration renders'
                                           // time included)
  bool kept = false;
  int runs = 1;  // timed runs (3 where the first landed near the budget)
};

struct TuneResult {
  Params params;                // the chosen configuration
  ConfigResult chosen;          // its measurements
  std::vector<TuneStep> steps;  // every configuration measured, in order
  std::string layer, goal;      // the objective, and what was sought
  nlohmann::json preset;        // to write: the parameters plus "tuned" (what and how)
};

TuneResult run_tune(const TuneSettings& s,
                    const std::function<void(const std::string&)>& progress = {});

}  // namespace hbil::pipeline
