// tune.cpp: `hbil tune SHOT --ref LAYER=PATTERN:EXPR ... -o preset.json`: a preset for the
// user's shot (pipeline/tune.h).
#include "pipeline/tune.h"

#include <tbb/global_control.h>

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
  std::string shot, output, frames, layer, mask = "auto";
  std::vector<std::string> refs;
  double budget = 0, tolerance = 0.1;
  int threads = 0;
  bool quiet = false;
  ParamOptions params;
};

void tune(const TuneOptions& o) {
  pipeline::TuneSettings s;
  s.bench.shot = o.shot;
  s.bench.frames = o.frames;
  s.bench.mask.mask = o.mask;
  for (const std::string& r : o.refs) s.bench.refs.push_back(pipeline::parse_bench_reference(r));
  const Params base = o.params.load();
  s.bench.mask.background_depth = base.background_depth;
  s.bench.configs = {{"base", base}};
  s.layer = o.layer;
  s.budget = o.budget;
  s.tolerance_db = o.tolerance;
  std::unique_ptr<tbb::global_control> threads;
  if (o.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    o.threads);
  // Nothing is written unless the search completes; the file appears whole or not at all.
  const std::string tmp = io::prepare_temporary(o.output);
  const pipeline::TuneResult r = pipeline::run_tune(s, [&](const std::string& line) {
    if (!o.quiet) std::cerr << "hbil: " << line << "\n";
  });
  {
    std::ofstream out(tmp);
    out << r.preset.dump(2) << "\n";
    if (!out.flush()) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw Error(Exit::output, o.output + ": cannot write");
    }
  }
  io::commit(tmp, o.output);
  std::printf("%s: %s, %s %.2f dB at %.3f s per frame (%zu configurations measured)\n",
              o.output.c_str(), r.goal.c_str(), r.layer.c_str(), r.chosen.errors.at(r.layer).psnr(),
              r.chosen.seconds_per_frame, r.steps.size());
}

}  // namespace

void add_tune(CLI::App& app) {
  auto o = std::make_shared<TuneOptions>();
  CLI::App* cmd = app.add_subcommand(
      "tune", "search a preset for a shot against its references and write it as JSON");
  cmd->add_option("SHOT", o->shot, "input EXR frame pattern (or one file), as for run")->required();
  cmd->add_option("-o,--output", o->output, "the preset file to write (JSON)")->required();
  cmd->add_option("--ref", o->refs,
                  "LAYER=PATTERN:EXPRESSION, as for bench; repeatable, at least one")
      ->required()
      ->allow_extra_args(false);
  cmd->add_option("--layer", o->layer,
                  "the layer whose PSNR is the objective (default: composite when referenced, "
                  "else the first --ref)");
  cmd->add_option("--budget", o->budget,
                  "seconds per frame: the most accurate preset within it (default: none, the "
                  "cheapest within --tolerance of the most accurate found)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--tolerance", o->tolerance, "dB below the best still accepted without --budget")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--frames", o->frames, "frame range A-B or one frame N (default: all found)");
  cmd->add_option("--mask", o->mask,
                  "valid pixels: auto (reference depth, else alpha), none, or a channel name")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")
      ->default_val(0)
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("-q,--quiet", o->quiet, "no progress lines");
  o->params.add_to(*cmd);
  cmd->callback([o] { tune(*o); });
}

}  // namespace hbil::cli
