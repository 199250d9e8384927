// ao_bench.cpp: throughput of the AO / bent-cone chain (Google Benchmark).
//
// The scene is ray cast analytically (a V-groove with a slanted occluder, tests/
// analytic_scenes.h) so the benchmark needs no files. Counters:
//   horizon_samples/s  depth samples marched per second (pixels x slices x 2 sides x steps)
//   Mpixels/s          frame pixels per second
// Arguments: width, height, steps, slices per pixel, interleave (1/0).
#include <benchmark/benchmark.h>

#include <numbers>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"

namespace {

using namespace hbil;

struct Scene {
  Camera cam;
  GBuffer g;
};

const Scene& scene(int w, int h) {
  static std::map<std::pair<int, int>, Scene> cache;
  auto it = cache.find({w, h});
  if (it != cache.end()) return it->second;
  Scene s;
  s.cam = test::look_at(w, h, 60, {0.4, 2.0, 1.5}, {0, 0, 0.2});
  std::vector<test::HalfPlane> planes = test::v_groove(75 * std::numbers::pi / 180);
  planes.push_back({{0.3, 0.5, 0.1}, {0.6, 0.0, 0.8}, {0, 0, 1}});
  s.g = test::ray_cast(s.cam, planes);
  return cache.emplace(std::make_pair(w, h), std::move(s)).first->second;
}

void BM_AoFrame(benchmark::State& state) {
  const int w = int(state.range(0)), h = int(state.range(1));
  Params p;
  p.method = "horizon";  // the README's throughput table is for the horizon kernel
  p.steps = int(state.range(2));
  p.slices = int(state.range(3));
  p.interleave = state.range(4) != 0;
  const Scene& s = scene(w, h);
  const ViewGBuffer v = make_view_gbuffer(s.g, s.cam, p);
  for (auto _ : state) {
    AoFrame f = compute_ao_frame(v, s.g, s.cam, p);
    benchmark::DoNotOptimize(f.ao.data());
  }
  const double pixels = double(w) * h;
  state.counters["horizon_samples/s"] = benchmark::Counter(
      pixels * p.slices * 2 * p.steps, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["Mpixels/s"] =
      benchmark::Counter(pixels * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

// Resolution scaling at the default settings.
BENCHMARK(BM_AoFrame)
    ->Args({256, 144, 12, 2, 1})
    ->Args({960, 540, 12, 2, 1})
    ->Args({1920, 1080, 12, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Cost against steps per side and slices per pixel, at 960x540.
BENCHMARK(BM_AoFrame)
    ->Args({960, 540, 6, 2, 1})
    ->Args({960, 540, 24, 2, 1})
    ->Args({960, 540, 48, 2, 1})
    ->Args({960, 540, 12, 4, 1})
    ->Args({960, 540, 12, 8, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Reference mode (every pixel, 32 slices) against interleaved at equal directions per block.
BENCHMARK(BM_AoFrame)->Args({960, 540, 12, 32, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
