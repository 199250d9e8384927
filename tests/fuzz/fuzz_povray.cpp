// fuzz_povray.cpp: the POV-Ray pass importer (`hbil import-povray`) on one frame of three
// files: camera1.json, depth1.exr and normal1.exr. The first byte of the input chooses
// which file the rest of the bytes become; the other two are the seed frame's own
// (tests/fuzz/corpus/povray/ holds the frame, one file per input). Findings: a signal or
// sanitizer report, an exception that is not hbil::Error, an internal error, or an
// imported pixel that is not finite.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>

#include "fuzz_util.h"
#include "hbil/error.h"
#include "io/povray.h"

namespace {

const char* const kFiles[] = {"camera1.json", "depth1.exr", "normal1.exr"};

std::string read_seed(const char* name) {
  std::ifstream in(std::string(HBIL_FUZZ_POVRAY_FRAME) + "/" + name, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "fuzz_povray: cannot read the seed frame's %s\n", name);
    std::abort();
  }
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace hbil;
  static const std::string seeds[] = {read_seed(kFiles[0]), read_seed(kFiles[1]),
                                      read_seed(kFiles[2])};
  if (size == 0) return 0;
  const int which = data[0] % 3;
  for (int k = 0; k < 3; ++k) {
    const std::string& s = seeds[k];
    if (k == which)
      fuzz::write_scratch(kFiles[k], data + 1, size - 1);
    else
      fuzz::write_scratch(kFiles[k], reinterpret_cast<const uint8_t*>(s.data()), s.size());
  }
  try {
    const auto frames = io::find_povray_frames(fuzz::scratch_dir().string());
    for (const auto& f : frames) {
      const io::ImportedFrame imp = io::import_povray_frame(f);
      for (float v : imp.pixels)
        if (!std::isfinite(v)) {
          std::fprintf(stderr, "fuzz_povray: imported a non-finite value\n");
          std::abort();
        }
    }
  } catch (const Error& e) {
    if (e.code() == Exit::failure) {
      std::fprintf(stderr, "fuzz_povray: internal error: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
