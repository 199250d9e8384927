// commands.h: the subcommands of the hbil command line. Each registers its options on a
// CLI11 subcommand and runs when it is chosen; errors are thrown as hbil::Error and turned
// into a message and an exit code by main() alone.
#pragma once

#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "hbil/params.h"
#include "pipeline/frame_output.h"

namespace hbil::cli {

// Options shared by the commands that take parameters.
struct ParamOptions {
  std::string preset;
  std::vector<std::string> sets;
  // Shorthands for the most used keys; their help shows the defaults of hbil::Params.
  double radius = Params{}.radius;
  int slices = Params{}.slices, steps = Params{}.steps;
  CLI::Option *radius_opt = nullptr, *slices_opt = nullptr, *steps_opt = nullptr;
  void add_to(CLI::App& app);
  // Defaults, then the preset file, then each --set in order. Throws Error(Exit::preset).
  Params load() const;
};

// What bench and tune are given of a shot: its frames, the references (--ref), the mask,
// threads and quietness.
struct ShotOptions {
  std::string shot, frames, mask = "auto";
  std::vector<std::string> refs;
  int threads = 0;
  bool quiet = false;
  void add_to(CLI::App& cmd, const std::string& ref_help);
  // A TBB limit for --threads N (null for 0: all cores), held while the command runs.
  std::unique_ptr<tbb::global_control> limit_threads() const;
};

// A check for an option that takes a count: a whole number >= `least` (0 or 1); else
// CLI11's error "<option>: must be <meaning>" (e.g. "0 (all cores) or a positive count"),
// exit 2.
CLI::Validator count_check(const std::string& meaning, int least = 0);
// The same for a number of seconds or decibels: finite and >= 0.
CLI::Validator amount_check(const std::string& meaning);
inline const std::string kThreadsMeaning = "0 (all cores) or a positive count";

// What a `run` command line asks for, read without running it: `args` are run's options after
// INPUT. Those a farm plan sets itself (--frames, --preroll, --cut-frames, --threads,
// --skip-existing, --log-json) are refused. Throws Error(Exit::usage, "<context>: ..."), or
// Error(Exit::preset) for the parameters.
struct RunRequest {
  pipeline::OutputSettings output;
  Params params;
};
RunRequest read_run_request(const std::string& input, const std::vector<std::string>& args,
                            const std::string& context);

// `hbil run INPUT args...`, as if given on the command line (CLI11's errors are
// Error(Exit::usage, "<context>: ...")).
void run_command(const std::string& input, const std::vector<std::string>& args,
                 const std::string& context);

void add_run(CLI::App& app);
void add_farm(CLI::App& app);
void add_bench(CLI::App& app);
void add_tune(CLI::App& app);
void add_info(CLI::App& app);
void add_compare(CLI::App& app);
void add_preset(CLI::App& app);
void add_import_povray(CLI::App& app);

}  // namespace hbil::cli
