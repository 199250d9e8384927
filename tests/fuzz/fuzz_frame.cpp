// fuzz_frame.cpp: an input frame from bytes, through everything `hbil run` does with it
// short of writing: the header and its channels, the fields the outputs need, the pixel
// checks, the camera (EXR attributes or solved from Position: no sidecar lies beside the
// file), the scene-scale "auto" values, and the computation of every output.
//
// A finding is: a signal or sanitizer report; an exception that is not hbil::Error; an
// hbil::Error with exit 1 (internal error); an output value that is not finite.
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "fuzz_util.h"
#include "hbil/error.h"
#include "pipeline/sequence_job.h"

namespace {

void require_finite(const std::vector<float>& v, const char* layer) {
  for (float x : v)
    if (!std::isfinite(x)) {
      std::fprintf(stderr, "fuzz_frame: non-finite value in output layer %s\n", layer);
      std::abort();
    }
}
void require_finite(const std::vector<hbil::Vec3>& v, const char* layer) {
  for (const hbil::Vec3& x : v)
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) {
      std::fprintf(stderr, "fuzz_frame: non-finite value in output layer %s\n", layer);
      std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace hbil;
  static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const std::string path = fuzz::write_scratch("frame_0001.exr", data, size);
  // Outputs "auto" (every layer the frame's passes allow), few steps: the fuzzer wants many inputs
  // a second, not accuracy.
  Params p;
  p.steps = 4;
  p.gather_steps = 4;
  p.slices = 1;
  try {
    const pipeline::SequencePlan plan = pipeline::plan_sequence(path, "", 0, "");
    const pipeline::SequenceJob job(plan, p);
    pipeline::SequenceJob::Hooks hooks;
    hooks.deliver = [](pipeline::FrameResult& r) {
      const AoFrame& f = r.outputs;
      require_finite(f.ao, "ao");
      require_finite(f.bent, "bentcone");
      require_finite(f.cone_cos, "bentcone");
      require_finite(f.irradiance, "irradiance");
      require_finite(f.indirect, "indirect");
      require_finite(f.composite, "composite");
      require_finite(f.composite_alpha, "composite");
    };
    job.run(hooks, pipeline::Overlap::off);
  } catch (const Error& e) {
    if (e.code() == Exit::failure) {
      std::fprintf(stderr, "fuzz_frame: internal error: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
