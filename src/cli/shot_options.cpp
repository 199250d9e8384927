// shot_options.cpp: the options bench and tune share (commands.h).
#include "cli/commands.h"

namespace hbil::cli {

void ShotOptions::add_to(CLI::App& cmd, const std::string& ref_help) {
  cmd.add_option("SHOT", shot, "input EXR frame pattern (or one file), as for run")->required();
  cmd.add_option("--ref", refs, ref_help)->required()->allow_extra_args(false);
  cmd.add_option("--frames", frames, "frame range A-B or one frame N (default: all found)");
  cmd.add_option("--mask", mask,
                 "valid pixels: auto (reference depth, else alpha), none, or a channel name")
      ->capture_default_str();
  cmd.add_option("--threads", threads, "worker threads (0 = all cores)")
      ->default_val(0)
      ->check(CLI::NonNegativeNumber);
  cmd.add_flag("-q,--quiet", quiet, "no progress lines");
}

std::unique_ptr<tbb::global_control> ShotOptions::limit_threads() const {
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               threads);
}

}  // namespace hbil::cli
