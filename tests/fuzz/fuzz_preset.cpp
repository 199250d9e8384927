// fuzz_preset.cpp: a preset file (--preset) from bytes, or, for an input that starts with
// "--set ", one --set assignment applied to the defaults. Findings: a signal or sanitizer
// report, an exception that is not hbil::Error, an internal error, or accepted parameters
// that do not come back the same through the JSON hbil writes for them (`hbil preset`).
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "fuzz_util.h"
#include "hbil/error.h"
#include "io/preset_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace hbil;
  static const char kSet[] = "--set ";
  Params p;
  try {
    if (size >= sizeof kSet - 1 && std::memcmp(data, kSet, sizeof kSet - 1) == 0)
      p = apply_set(Params{}, std::string(reinterpret_cast<const char*>(data) + sizeof kSet - 1,
                                          size - (sizeof kSet - 1)));
    else
      p = io::read_preset(fuzz::write_scratch("preset.json", data, size));
  } catch (const Error& e) {
    if (e.code() != Exit::failure) return 0;
    std::fprintf(stderr, "fuzz_preset: internal error: %s\n", e.what());
    std::abort();
  }
  // Accepted: what hbil writes for it must read back, to the same parameters.
  const nlohmann::json written = to_json(p);
  try {
    if (to_json(params_from_json(written, "written")) == written) return 0;
    std::fprintf(stderr, "fuzz_preset: parameters do not read back the same\n");
  } catch (const Error& e) {
    std::fprintf(stderr, "fuzz_preset: hbil's own JSON for them is refused: %s\n", e.what());
  }
  std::abort();
}
