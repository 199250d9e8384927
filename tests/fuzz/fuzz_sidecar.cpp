// fuzz_sidecar.cpp: a camera sidecar (<frame>.camera.json) from bytes, read as `hbil run`
// reads the one beside a frame. Findings: a signal or sanitizer report, an exception that
// is not hbil::Error, or a camera accepted with a non-finite value or no resolution.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "fuzz_util.h"
#include "hbil/error.h"
#include "io/camera_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace hbil;
  const std::string path = fuzz::write_scratch("frame_0001.camera.json", data, size);
  try {
    const Camera c = io::camera_from_sidecar(path);
    double v[] = {c.fx, c.fy, c.cx, c.cy, c.t.x, c.t.y, c.t.z};
    bool finite = c.width > 0 && c.height > 0;
    for (double x : v) finite = finite && std::isfinite(x);
    for (const auto& row : c.R.m)
      for (double x : row) finite = finite && std::isfinite(x);
    if (!finite) {
      std::fprintf(stderr, "fuzz_sidecar: accepted a camera with a non-finite value or no size\n");
      std::abort();
    }
  } catch (const Error& e) {
    if (e.code() == Exit::failure) std::abort();
  }
  return 0;
}
