// tune.cpp: `hbil tune SHOT --ref LAYER=PATTERN:EXPR ... -o preset.json`: a preset for the
// user's shot (pipeline/tune.h).
#include "pipeline/tune.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "cli/commands.h"
#include "hbil/error.h"
#include "io/exr_output.h"

namespace hbil::cli {

namespace {

struct TuneOptions {
  ShotOptions shot;
  std::string output, layer;
  double budget = 0, tolerance = 0.1;
  std::vector<std::string> keys;
  ParamOptions params;
};

void tune(const TuneOptions& o) {
  pipeline::TuneSettings s;
  s.bench.shot = o.shot.shot;
  s.bench.frames = o.shot.frames;
  s.bench.mask.mask = o.shot.mask;
  for (const std::string& r : o.shot.refs)
    s.bench.refs.push_back(pipeline::parse_bench_reference(r));
  const Params base = o.params.load();
  s.bench.mask.background_depth = base.background_depth;
  s.bench.configs = {{"base", base}};
  s.layer = o.layer;
  s.budget = o.budget;
  s.tolerance_db = o.tolerance;
  for (const std::string& k : o.keys) {
    size_t start = 0;
    while (start <= k.size()) {
      const size_t comma = std::min(k.find(',', start), k.size());
      if (comma > start) s.keys.push_back(k.substr(start, comma - start));
      start = comma + 1;
    }
  }
  const auto threads = o.shot.limit_threads();
  // Nothing is written (no folder either) unless the search completes; the file appears
  // whole or not at all.
  const pipeline::TuneResult r = pipeline::run_tune(s, [&](const std::string& line) {
    if (!o.shot.quiet) std::cerr << "hbil: " << line << "\n";
  });
  io::write_file(o.output, r.preset.dump(2) + "\n");
  std::printf("%s: %s, %s %.2f dB at %.3f s per frame (%zu configurations measured)\n",
              o.output.c_str(), r.goal.c_str(), r.layer.c_str(), r.chosen.errors.at(r.layer).psnr(),
              r.chosen.cost_per_frame(), r.steps.size());
}

}  // namespace

void add_tune(CLI::App& app) {
  auto o = std::make_shared<TuneOptions>();
  CLI::App* cmd = app.add_subcommand(
      "tune", "search a preset for a shot against its references and write it as JSON");
  cmd->add_option("-o,--output", o->output, "the preset file to write (JSON)")->required();
  o->shot.add_to(*cmd, "LAYER[@TAG]=PATTERN:EXPRESSION, as for bench; repeatable, at least one");
  cmd->add_option("--layer", o->layer,
                  "the layer whose PSNR is the objective (default: composite when referenced, "
                  "else the first --ref)");
  cmd->add_option("--budget", o->budget,
                  "seconds per frame: the most accurate preset within it (default: none, the "
                  "cheapest within --tolerance of the most accurate found)")
      ->check(amount_check("a number of seconds >= 0"));
  cmd->add_option("--tolerance", o->tolerance, "dB below the best still accepted without --budget")
      ->capture_default_str()
      ->check(amount_check("a number of decibels >= 0"));
  cmd->add_option("--keys", o->keys,
                  "k1,k2,...: search only these keys (of method, slices, steps, gather_steps, "
                  "gather_radius, thickness, gather_thickness, unseen_radiance, unseen_carry; "
                  "default: all)")
      ->allow_extra_args(false);
  o->params.add_to(*cmd);
  cmd->callback([o] { tune(*o); });
}

}  // namespace hbil::cli
