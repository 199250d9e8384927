// ao_bench.cpp: throughput of the horizon search at the default preset, of a whole frame and
// of reading one (Google Benchmark).
//
// The frame is a real Blender render: samples/room_poles/frame_0003.exr (256x144), or the
// EXR named by $HBIL_BENCH_FRAME (with its camera sidecar beside it), e.g. a 1920x1080
// render of samples/blender/room_poles.py --size 1920x1080. What is timed is the search of
// one frame (search_frame: the march of every pixel, interleaved, and the spatial filter),
// the part `hbil run -v` reports inside "compute". Counters:
//   samples/s   depth samples marched per second: searched pixels x slices x 2 sides x steps,
//               plus gather_steps per side when the irradiance gather runs (searched pixels:
//               the frame's, or 1/n² of them with search_scale n)
//   Mpixels/s   frame pixels per second
// Arguments: gather (0: ao and bentcone only, 1: with the irradiance gather), vectorised
// (1: SIMD march, 0: the scalar reference), steps per side, search_scale (0: auto, the
// default; 1: every pixel). BM_March times the march alone (the kernel), BM_Frame the whole
// single-frame computation (default outputs or ao + bentcone), BM_Read the reading of the frame's
// fields for them (what `hbil run -v` reports as "read"; file MB/s counts the whole file, every
// channel of which is decompressed), BM_Reproject the temporal chain's reprojection of its
// history into the frame.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>

#include "hbil/ao_frame.h"
#include "hbil/interleave.h"
#include "hbil/reduced.h"
#include "hbil/reproject.h"
#include "io/camera_io.h"
#include "io/exr_frame.h"

namespace {

using namespace hbil;

struct Frame {
  GBuffer g;
  Camera cam;
  std::vector<Vec3> radiance;
};

std::string frame_path() {
  const char* env = std::getenv("HBIL_BENCH_FRAME");
  return env ? env : std::string(HBIL_SOURCE_DIR) + "/samples/room_poles/frame_0003.exr";
}

const Frame& frame() {
  static const Frame f = [] {
    const std::string path = frame_path();
    Params p;
    p.outputs = {"ao", "bentcone", "irradiance"};
    const io::InputFrame in = io::open_frame(path, 3, p);
    Frame r;
    r.g = io::read_fields(in, io::fields_needed(in, p), p);
    r.cam = io::find_camera(in, r.g, p);
    return r;
  }();
  return f;
}

void BM_Search(benchmark::State& state) {
  const bool gather = state.range(0) != 0;
  Params p;  // the default preset
  p.vectorised = state.range(1) != 0;
  p.steps = int(state.range(2));
  p.search_scale = int(state.range(3));
  p.outputs = gather ? std::vector<std::string>{"ao", "bentcone", "irradiance"}
                     : std::vector<std::string>{"ao", "bentcone"};
  const Frame& f = frame();
  const ViewGBuffer v = make_view_gbuffer(f.g, f.cam, p);
  for (auto _ : state) {
    HorizonImage h = search_frame(v, f.g, f.cam, p, FrameInputs{});
    benchmark::DoNotOptimize(h.ao.data());
  }
  const double pixels = double(f.g.width) * f.g.height;
  const int n = effective_search_scale(p, f.g.width, f.g.height);
  const double searched =
      double(reduced_extent(f.g.width, n)) * double(reduced_extent(f.g.height, n));
  const int per_side = p.steps + (gather ? p.gather_steps : 0);
  state.counters["samples/s"] = benchmark::Counter(searched * p.slices * 2 * per_side,
                                                   benchmark::Counter::kIsIterationInvariantRate);
  state.counters["Mpixels/s"] =
      benchmark::Counter(pixels * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(std::to_string(f.g.width) + "x" + std::to_string(f.g.height) + ", search 1 in " +
                 std::to_string(n) + "x" + std::to_string(n));
}

// What BM_March and BM_Record march: the texels search_frame marches (the reduced view at the
// default search_scale) with the default preset's configuration, and a constant source radiance
// for the gather (the march's cost does not depend on its values).
struct MarchInput {
  Params p;
  int n = 1;  // search_scale
  ViewGBuffer v, lo;
  HorizonConfig c;
  std::vector<Vec3> radiance;
  explicit MarchInput(bool gather) {
    p.outputs = gather ? std::vector<std::string>{"ao", "bentcone", "irradiance"}
                       : std::vector<std::string>{"ao", "bentcone"};
    const Frame& f = frame();
    v = make_view_gbuffer(f.g, f.cam, p);
    n = effective_search_scale(p, v.width, v.height);
    if (n > 1) lo = reduce_view(v, n);
    c = make_horizon_config(p, f.cam);
    radiance.assign(texels().pixels(), Vec3{0.5f, 0.5f, 0.5f});
  }
  const ViewGBuffer& texels() const { return n > 1 ? lo : v; }
  // Counter samples/s (as BM_Search's, over the texels marched) and the label.
  void count(benchmark::State& state, bool gather) const {
    const ViewGBuffer& sv = texels();
    const int per_side = p.steps + (gather ? p.gather_steps : 0);
    state.counters["samples/s"] = benchmark::Counter(double(sv.pixels()) * p.slices * 2 * per_side,
                                                     benchmark::Counter::kIsIterationInvariantRate);
    state.SetLabel(std::to_string(sv.width) + "x" + std::to_string(sv.height) + " texels marched");
  }
};

// The march alone, the kernel: horizon_interleaved on MarchInput's texels, without the spatial
// filter and the upsample around it, which BM_Search includes.
void BM_March(benchmark::State& state) {
  const bool gather = state.range(0) != 0;
  const MarchInput in(gather);
  for (auto _ : state) {
    HorizonImage h =
        horizon_interleaved(in.texels(), in.c, in.p.slices, gather ? &in.radiance : nullptr);
    benchmark::DoNotOptimize(h.ao.data());
  }
  in.count(state, gather);
}
BENCHMARK(BM_March)
    ->ArgNames({"gather"})
    ->Args({0})
    ->Args({1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The recorded gather (interleave.h, GatherRecord), as the calibration's solve and the later
// in-frame bounces use it: argument 0 marches with the gather and no record (BM_March's
// gather row), 1 marches and records into an empty record, 2 replays a filled record (sums
// it with the radiance, no march). Counters as BM_March's, and the record's entries.
void BM_Record(benchmark::State& state) {
  const int mode = int(state.range(0));
  const MarchInput in(true);
  auto search = [&](GatherRecord* r) {
    return horizon_interleaved(in.texels(), in.c, in.p.slices, &in.radiance, true, r);
  };
  GatherRecord filled;
  if (mode == 2) search(&filled);
  size_t entries = 0;
  for (auto _ : state) {
    GatherRecord fresh;
    HorizonImage h = search(mode == 0 ? nullptr : mode == 1 ? &fresh : &filled);
    benchmark::DoNotOptimize(h.irradiance.data());
    entries = 0;
    for (const GatherLog& row : (mode == 2 ? filled : fresh).rows) entries += row.entries.size();
  }
  in.count(state, true);
  state.counters["entries"] = double(entries);
}
BENCHMARK(BM_Record)
    ->ArgNames({"mode"})
    ->Args({0})
    ->Args({1})
    ->Args({2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The view-space G-buffer of the frame (make_view_gbuffer, from its depth pass): argument 1
// the SIMD rows, 0 the scalar loop (`vectorised`); the same buffer to the bit.
void BM_ViewGBuffer(benchmark::State& state) {
  Params p;
  p.vectorised = state.range(0) != 0;
  const Frame& f = frame();
  for (auto _ : state) {
    ViewGBuffer v = make_view_gbuffer(f.g, f.cam, p);
    benchmark::DoNotOptimize(v.position.data());
  }
  state.counters["Mpixels/s"] = benchmark::Counter(double(f.g.pixels()) * 1e-6,
                                                   benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ViewGBuffer)
    ->ArgNames({"simd"})
    ->Args({0})
    ->Args({1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The whole single-frame computation (compute_ao_frame: view-space G-buffer, search, spatial
// filter, outputs), what `hbil run -v --set temporal=false` reports as "compute".
void BM_Frame(benchmark::State& state) {
  Params p;
  p.temporal = false;
  if (state.range(0) == 0) p.outputs = {"ao", "bentcone"};
  const Frame& f = frame();
  for (auto _ : state) {
    AoFrame out = compute_ao_frame(f.g, f.cam, p);
    benchmark::DoNotOptimize(out.ao.data());
  }
  state.counters["Mpixels/s"] = benchmark::Counter(double(f.g.width) * f.g.height * 1e-6,
                                                   benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(std::to_string(f.g.width) + "x" + std::to_string(f.g.height));
}
// The temporal chain's reprojection through the motion vectors (reproject_gather) of a history
// of 6 channels (ao + bentcone) or 9 (with irradiance): the frame's view-space G-buffer stands
// for the previous one too, with its own Vector pass (the cost does not depend on the values).
void BM_Reproject(benchmark::State& state) {
  const int channels = int(state.range(0));
  Params p;
  const Frame& f = frame();
  const ViewGBuffer v = make_view_gbuffer(f.g, f.cam, p);
  const std::vector<float> motion =
      f.g.motion.empty() ? std::vector<float>(2 * v.pixels(), 0.25f) : f.g.motion;
  std::vector<float> history(v.pixels() * size_t(channels));
  for (size_t i = 0; i < history.size(); ++i) history[i] = float(i % 97) / 97.f;
  const ReprojectTolerance tol{float(p.history_depth_tolerance), float(p.history_normal_cos)};
  for (auto _ : state) {
    Reprojected r = reproject_gather(v, f.cam, history, channels, v, f.cam, motion, tol);
    benchmark::DoNotOptimize(r.value.data());
  }
  state.counters["Mpixels/s"] =
      benchmark::Counter(double(v.pixels()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(std::to_string(v.width) + "x" + std::to_string(v.height));
}
BENCHMARK(BM_Reproject)
    ->ArgNames({"channels"})
    ->Args({6})
    ->Args({9})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Reading the fields one frame's outputs need (open_frame + read_fields), from the page cache.
void BM_Read(benchmark::State& state) {
  Params p;
  if (state.range(0) == 0) p.outputs = {"ao", "bentcone"};
  const std::string path = frame_path();
  size_t pixels = 0;
  for (auto _ : state) {
    const io::InputFrame in = io::open_frame(path, 3, p);
    GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
    pixels = g.pixels();
    benchmark::DoNotOptimize(g.depth.data());
  }
  state.counters["Mpixels/s"] =
      benchmark::Counter(double(pixels) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["file MB/s"] = benchmark::Counter(double(std::filesystem::file_size(path)) * 1e-6,
                                                   benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Read)
    ->ArgNames({"default_outputs"})
    ->Args({0})
    ->Args({1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_Frame)
    ->ArgNames({"default_outputs"})
    ->Args({0})
    ->Args({1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The default preset (16 steps): AO only and with the gather, SIMD and scalar; and the SIMD
// march at every pixel (search_scale 1).
BENCHMARK(BM_Search)
    ->ArgNames({"gather", "simd", "steps", "scale"})
    ->Args({0, 1, 16, 0})
    ->Args({1, 1, 16, 0})
    ->Args({0, 0, 16, 0})
    ->Args({1, 0, 16, 0})
    ->Args({0, 1, 16, 1})
    ->Args({1, 1, 16, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Cost against steps per side (SIMD, AO only).
BENCHMARK(BM_Search)
    ->ArgNames({"gather", "simd", "steps", "scale"})
    ->Args({0, 1, 8, 0})
    ->Args({0, 1, 32, 0})
    ->Args({0, 1, 64, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
