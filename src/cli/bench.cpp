// bench.cpp: `hbil bench SHOT -o DIR --ref LAYER=PATTERN:EXPR ...`: speed against accuracy
// on the user's own shot (pipeline/bench.h).
#include "pipeline/bench.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli/commands.h"
#include "hbil/error.h"
#include "io/preset_file.h"

namespace hbil::cli {

namespace {

struct BenchOptions {
  ShotOptions shot;
  std::string out_dir;
  std::vector<std::string> presets, sets, sweeps, renders;
  int runs = 1;
  bool stability = false;
};

void bench(const BenchOptions& o) {
  pipeline::BenchSettings s;
  s.shot = o.shot.shot;
  s.frames = o.shot.frames;
  s.runs = o.runs;
  s.mask.mask = o.shot.mask;
  s.stability = o.stability;
  for (const std::string& r : o.shot.refs) s.refs.push_back(pipeline::parse_bench_reference(r));
  for (const std::string& r : o.renders) s.renders.push_back(pipeline::parse_bench_render(r));
  std::vector<pipeline::BenchConfig> bases;
  auto with_sets = [&](Params p) {
    for (const std::string& set : o.sets) p = apply_set(p, set);
    return p;
  };
  if (o.presets.empty()) bases.push_back({"default", with_sets(Params{})});
  for (const std::string& f : o.presets)
    bases.push_back({std::filesystem::path(f).stem().string(), with_sets(io::read_preset(f))});
  s.configs = pipeline::expand_sweeps(bases, o.sweeps);
  s.mask.background_depth = s.configs.front().params.background_depth;
  const auto threads = o.shot.limit_threads();
  const pipeline::BenchResult r = pipeline::run_bench(s, [&](const std::string& line) {
    if (!o.shot.quiet) std::cerr << "hbil: " << line << "\n";
  });
  pipeline::write_bench(r, o.out_dir);
  // The table: a row per configuration; per layer its PSNR, * on the Pareto front.
  // With a calibration, its renders' time per frame is part of the cost (the Pareto fronts and
  // the speedup count it): a column of its own.
  const bool calibrated =
      std::any_of(r.configs.begin(), r.configs.end(), [](const auto& c) { return c.calibrated; });
  std::printf("%-32s %9s", "configuration", "s/frame");
  if (calibrated) std::printf(" %9s", "+cal s");
  for (const std::string& l : r.layers) std::printf(" %12s", (l + " dB").c_str());
  if (!r.renders.empty()) std::printf(" %14s", "speedup");
  std::printf("\n");
  for (const pipeline::ConfigResult& c : r.configs) {
    std::printf("%-32s %9.3f", c.name.c_str(), c.seconds_per_frame);
    if (calibrated) {
      if (!c.calibrated)
        std::printf(" %9s", "-");
      else if (c.calibration_seconds >= 0)
        std::printf(" %9.4f", c.calibration_seconds);
      else
        std::printf(" %9s", "unknown");
    }
    for (const std::string& l : r.layers)
      std::printf(" %11.2f%s", c.errors.at(l).psnr(), c.pareto.at(l) ? "*" : " ");
    if (!r.renders.empty()) {
      char b[32];
      std::snprintf(b, sizeof b, "%s%.1fx", c.speedup_bound.c_str(), c.speedup);
      std::printf(" %14s", c.speedup > 0 ? b : "-");
    }
    std::printf("\n");
  }
  if (!r.configs.empty() && r.configs.front().has_stability) {
    std::printf(
        "\nstability (%s): flicker, RMSE revealed / other, cut (frames to recover), "
        "RMSE edge / interior, RMSE thin / rest, bad pixels\n",
        r.configs.front().stability.layer.c_str());
    for (const pipeline::ConfigResult& c : r.configs) {
      const pipeline::StabilityFigures& f = c.stability;
      std::printf("%-32s %.5f  %.4f / %.4f  %s (%d)  %.4f / %.4f  %.4f / %.4f  %s\n",
                  c.name.c_str(), f.flicker, f.revealed_rmse, f.other_rmse,
                  f.cut_detected ? "detected" : "missed", f.cut_recovery_frames, f.edge_rmse,
                  f.interior_rmse, f.thin_rmse, f.rest_rmse, f.robust ? "robust" : "NOT robust");
    }
  }
  for (const pipeline::RenderResult& x : r.renders)
    std::printf("%-32s %9.3f %11.2f  (render, %d samples)\n", x.pattern.c_str(),
                x.seconds_per_frame, x.error.psnr(), x.samples);
  std::printf(
      "* on the layer's Pareto front; %s; written to %s (bench.json, bench.csv, "
      "chart.svg, chart.png)\n",
      r.machine.c_str(), o.out_dir.c_str());
  if (calibrated)
    std::printf(
        "+cal s: the calibration renders' own time from their headers, per frame, counted in "
        "the Pareto fronts, the chart and the speedup (unknown: a render without one, not "
        "counted)\n");
}

}  // namespace

void add_bench(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "speed against accuracy of presets and parameter sweeps on a shot, with a chart");
  cmd->add_option("-o,--output", o->out_dir,
                  "folder for bench.json, bench.csv, chart.svg and chart.png")
      ->required();
  o->shot.add_to(*cmd,
                 "LAYER[@TAG]=PATTERN:EXPRESSION: a layer's reference, e.g. "
                 "ao='ref/frame_####.exr:AO', indirect='ref/frame_####.exr:DiffCol*DiffInd'; "
                 "repeatable, at least one (a tag names a second reference for the same "
                 "layer: indirect@1bounce=...)");
  cmd->add_option("--render", o->renders,
                  "PATTERN[:EXPRESSION]: a path-traced render of the frames (default "
                  "expression Combined) with its render time in the header; repeatable (one "
                  "per sample count); needs --ref composite=...")
      ->allow_extra_args(false);
  cmd->add_option("--preset", o->presets,
                  "a configuration from this preset file; repeatable (default: the defaults)")
      ->allow_extra_args(false);
  cmd->add_option("--set", o->sets, "key=value applied to every configuration, as in run")
      ->allow_extra_args(false);
  cmd->add_option("--sweep", o->sweeps,
                  "key=v1,v2,...: every configuration with each value; repeatable (the "
                  "combinations of all sweeps)")
      ->allow_extra_args(false);
  cmd->add_option("--runs", o->runs, "timed runs per configuration, alternated (medians)")
      ->default_val(1)
      ->check(count_check("a positive number of runs", 1));
  cmd->add_flag("--stability", o->stability,
                "also the stability figures: flicker, revealed pixels, cut, screen edge, thin "
                "objects, bad pixels (stability.csv; man hbil, bench)");
  cmd->callback([o] { bench(*o); });
}

}  // namespace hbil::cli
