// shot_options.cpp: the options bench and tune share (commands.h).
#include <charconv>
#include <cmath>

#include "cli/commands.h"

namespace hbil::cli {

CLI::Validator count_check(const std::string& meaning, int least) {
  return CLI::Validator(
      [meaning, least](std::string& text) -> std::string {
        int v = -1;
        const char* end = text.data() + text.size();
        const auto [ptr, ec] = std::from_chars(text.data(), end, v);
        if (ec != std::errc() || ptr != end || v < least)
          return "must be " + meaning + ", got \"" + text + "\"";
        return "";
      },
      "COUNT");
}

CLI::Validator amount_check(const std::string& meaning) {
  return CLI::Validator(
      [meaning](std::string& text) -> std::string {
        double v = -1;
        const char* end = text.data() + text.size();
        const auto [ptr, ec] = std::from_chars(text.data(), end, v);
        if (ec != std::errc() || ptr != end || !std::isfinite(v) || v < 0)
          return "must be " + meaning + ", got \"" + text + "\"";
        return "";
      },
      "NUMBER");
}

void ShotOptions::add_to(CLI::App& cmd, const std::string& ref_help) {
  cmd.add_option("SHOT", shot, "input EXR frame pattern (or one file), as for run")->required();
  cmd.add_option("--ref", refs, ref_help)->required()->allow_extra_args(false);
  cmd.add_option("--frames", frames,
                 "frames: N, A-B, A-BxSTEP, lists such as 1,3,5-8 (default: all found)");
  cmd.add_option("--mask", mask,
                 "valid pixels: auto (reference depth, else alpha), none, or a channel name")
      ->capture_default_str();
  cmd.add_option("--threads", threads, "worker threads (0 = all cores)")
      ->default_val(0)
      ->check(count_check(kThreadsMeaning));
  cmd.add_flag("-q,--quiet", quiet, "no progress lines");
}

std::unique_ptr<tbb::global_control> ShotOptions::limit_threads() const {
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               threads);
}

}  // namespace hbil::cli
