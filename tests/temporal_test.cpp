// temporal_test.cpp: the temporal chain (temporal.h) on analytic scenes: convergence of a
// static camera towards the many-bounce result, history kept through a camera rotation,
// cuts dropping the history.
#include "hbil/temporal.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"
#include "hbil/reproject.h"
#include "pipeline/sequence_job.h"
#include "test_util.h"

namespace hbil {
namespace {

constexpr double kPi = std::numbers::pi;

// A 90-degree groove: floor A (albedo 0.8, unlit) and wall B (albedo 0.8, direct light 1).
struct Scene {
  Camera cam;
  GBuffer g;
};
Scene groove(double yaw_deg = 0, int w = 96, int h = 96) {
  Scene s;
  s.g = test::lit_groove(s.cam, yaw_deg, w, h, 90);
  return s;
}

Params params() {
  Params p;
  p.outputs = {"ao", "irradiance"};
  return p;
}

double mean_abs_diff(const Scene& s, const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double sum = 0;
  int n = 0;
  for (size_t i = 0; i < s.g.pixels(); ++i)
    if (s.g.depth[i] < 1e9f) sum += std::fabs(a[i].x - b[i].x), ++n;
  return sum / n;
}

TEST(Temporal, StaticCameraConvergesTowardsTheManyBounceResult) {
  const Scene s = groove();
  Params many = params();
  many.bounces = 12;  // in-frame bounces: the converged multi-bounce irradiance
  const AoFrame ref = compute_ao_frame(s.g, s.cam, many);
  const AoFrame one = compute_ao_frame(s.g, s.cam, params());
  TemporalChain chain(params());
  std::vector<double> err;
  for (int frame = 1; frame <= 40; ++frame) {
    TemporalReport rep;
    const AoFrame f = chain.process(s.g, s.cam, frame, false, nullptr, &rep);
    if (frame > 1) EXPECT_GT(rep.history, 0.999) << frame;  // a static camera keeps it all
    err.push_back(mean_abs_diff(s, f.irradiance, ref.irradiance));
  }
  const double gap = mean_abs_diff(s, one.irradiance, ref.irradiance);
  RecordProperty("one_bounce_gap", std::to_string(gap));
  RecordProperty("error_frame_1_5_40", std::to_string(err[0]) + " " + std::to_string(err[4]) + " " +
                                           std::to_string(err.back()));
  // Measured: one-bounce gap 0.0171; error 0.0175 at frame 1 (one bounce, other slice
  // rotation), 0.0060 at frame 5, 0.0016 at frame 40 (interleaving noise and the history's lag).
  EXPECT_NEAR(err[0], gap, 0.05 * gap);  // frame 1 is the single-bounce result
  EXPECT_LT(err[4], 0.5 * err[0]);
  EXPECT_LT(err.back(), 0.15 * gap);
}

TEST(Temporal, CameraRotationKeepsTheHistory) {
  Params p = params();
  p.feedback = false;  // the same one-bounce quantity every frame
  const Scene a = groove(0), b = groove(2);
  TemporalChain chain(p);
  const AoFrame f1 = chain.process(a.g, a.cam, 1, false);
  TemporalReport rep;
  const AoFrame f = chain.process(b.g, b.cam, 2, false, nullptr, &rep);
  EXPECT_FALSE(rep.cut);
  EXPECT_EQ(rep.reprojection, "scatter");
  EXPECT_GT(rep.history, 0.9);  // all but the strip that turned into view
  // Frame 2 on its own (its slice rotation), and frame 1's result reprojected into it.
  FrameInputs in;
  in.rotate = true;
  in.frame = 2;
  const Params r = resolve_frame_outputs(b.g, p);
  const ViewGBuffer va = make_view_gbuffer(a.g, a.cam, r), v = make_view_gbuffer(b.g, b.cam, r);
  const AoFrame single =
      assemble_frame(v, b.g, b.cam, r, search_frame(v, b.g, b.cam, r, in), nullptr);
  std::vector<float> e1(3 * f1.irradiance.size());
  std::memcpy(e1.data(), f1.irradiance.data(), e1.size() * sizeof(float));
  const Reprojected h = reproject_scatter(
      va, a.cam, e1, 3, v, b.cam, {float(p.history_depth_tolerance), float(p.history_normal_cos)});
  // Where the history was accepted the pixel holds two frames: the plain mean of the two
  // (blend weight max(1/n, 1 − history_weight) = 1/2); elsewhere the single frame.
  const float w = std::max(0.5f, 1.f - float(p.history_weight));
  double off_blend = 0, blend_move = 0, frame_gap = 0;
  size_t with_history = 0;
  for (size_t i = 0; i < b.g.pixels(); ++i) {
    if (v.is_background(i)) continue;
    const float s = single.irradiance[i].x;
    const float expected = h.valid[i] ? h.value[3 * i] + w * (s - h.value[3 * i]) : s;
    off_blend = std::max(off_blend, double(std::fabs(f.irradiance[i].x - expected)));
    if (!h.valid[i]) continue;
    ++with_history;
    blend_move += std::fabs(f.irradiance[i].x - s);
    frame_gap += std::fabs(h.value[3 * i] - s);
  }
  ASSERT_GT(with_history, b.g.pixels() / 2);
  blend_move /= double(with_history);
  frame_gap /= double(with_history);
  RecordProperty("frame_gap", std::to_string(frame_gap));
  EXPECT_LT(off_blend, 1e-6) << "the result is the blend of the history and the frame";
  // The two frames' estimates differ (their slices are turned), so the blend moves the
  // result half way towards the history; a chain that did not accumulate stays at 0.
  EXPECT_GT(frame_gap, 1e-3);
  EXPECT_NEAR(blend_move, 0.5 * frame_gap, 1e-6);
  // And the history is of the same quantity: the blend stays near the single frame.
  EXPECT_LT(mean_abs_diff(b, f.irradiance, single.irradiance), 0.01);
}

TEST(Temporal, CutDropsTheHistory) {
  const Scene a = groove(0), far = groove(60);
  TemporalChain chain(params()), fresh(params()), fresh2(params());
  chain.process(a.g, a.cam, 1, false);
  chain.process(a.g, a.cam, 2, false);
  TemporalReport rep;
  const AoFrame cut = chain.process(far.g, far.cam, 3, false, nullptr, &rep);
  EXPECT_TRUE(rep.cut);
  EXPECT_NE(rep.cut_reason.find("camera turned"), std::string::npos) << rep.cut_reason;
  const AoFrame first = fresh.process(far.g, far.cam, 3, false);
  ASSERT_EQ(cut.ao.size(), first.ao.size());
  EXPECT_EQ(0, std::memcmp(cut.ao.data(), first.ao.data(), cut.ao.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(cut.irradiance.data(), first.irradiance.data(),
                           cut.irradiance.size() * sizeof(Vec3)));
  // A cut given by the caller, on the same view.
  const AoFrame given = chain.process(far.g, far.cam, 4, true, nullptr, &rep);
  EXPECT_TRUE(rep.cut);
  EXPECT_EQ(rep.cut_reason, "given");
  const AoFrame first4 = fresh2.process(far.g, far.cam, 4, false);
  EXPECT_EQ(0, std::memcmp(given.ao.data(), first4.ao.data(), given.ao.size() * sizeof(float)));
}

// slices "auto" in a chain (resolved to 1): a frame without history, the chain's first or
// the first after a cut, is searched with 2 slices as a single frame is; the frames with
// history march 1.
TEST(Temporal, SlicesAutoMarchesTwoWhereThereIsNoHistory) {
  const Scene a = groove(0), b = groove(2), far = groove(60);
  Params one_p = resolve_auto_slices(params(), true), two_p = params(), fixed_one = params();
  two_p.slices = 2, two_p.slices_auto = false;
  fixed_one.slices = 1, fixed_one.slices_auto = false;
  ASSERT_EQ(one_p.slices, 1);
  TemporalChain chain(one_p), two(two_p), two_cut(two_p), one(fixed_one);
  const AoFrame f1 = chain.process(a.g, a.cam, 1, false);
  test::expect_same_bytes(f1.ao, two.process(a.g, a.cam, 1, false).ao, "first frame ao");
  one.process(a.g, a.cam, 1, false);
  // Frame 2 has history: one slice. It differs from the 2-slice chain's frame 2, and from a
  // chain of one slice throughout only through what frame 1 accumulated.
  const AoFrame f2 = chain.process(b.g, b.cam, 2, false);
  const AoFrame t2 = two.process(b.g, b.cam, 2, false);
  const AoFrame o2 = one.process(b.g, b.cam, 2, false);
  auto differs = [](const std::vector<float>& x, const std::vector<float>& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(float)) != 0;
  };
  EXPECT_TRUE(differs(f2.ao, t2.ao));
  EXPECT_TRUE(differs(f2.ao, o2.ao));
  // After a cut: 2 slices again, as a fresh 2-slice chain's first frame.
  TemporalReport rep;
  const AoFrame c = chain.process(far.g, far.cam, 3, false, nullptr, &rep);
  ASSERT_TRUE(rep.cut);
  test::expect_same_bytes(c.ao, two_cut.process(far.g, far.cam, 3, false).ao, "after the cut");
  test::expect_same_bytes(c.irradiance,
                          TemporalChain(two_p).process(far.g, far.cam, 3, false).irradiance,
                          "irradiance after the cut");
}

TEST(Temporal, AutoOutputsAreResolvedOnTheFirstFrame) {
  const Scene s = groove();
  TemporalChain chain{Params{}};  // outputs "auto": the groove has DiffCol and DiffDir
  Params listed;
  listed.outputs = {"ao", "bentcone", "irradiance", "indirect", "composite"};
  TemporalChain explicit_chain{listed};
  for (int frame = 1; frame <= 2; ++frame) {
    SCOPED_TRACE(frame);
    const AoFrame f = chain.process(s.g, s.cam, frame, false);
    const AoFrame e = explicit_chain.process(s.g, s.cam, frame, false);
    // "auto" is exactly the five layers, computed as when they are listed.
    test::expect_same_bytes(f.ao, e.ao, "ao");
    test::expect_same_bytes(f.bent, e.bent, "bent");
    test::expect_same_bytes(f.irradiance, e.irradiance, "irradiance");
    test::expect_same_bytes(f.indirect, e.indirect, "indirect");
    test::expect_same_bytes(f.composite, e.composite, "composite");
    // The composite is DiffCol × (DiffDir + irradiance) (no Emit), and the unlit floor
    // receives light from the wall.
    double floor_e = 0;
    size_t floor_n = 0;
    for (size_t i = 0; i < s.g.pixels(); ++i) {
      if (!(s.g.depth[i] < 1e9f)) continue;
      const float expected = 0.8f * (s.g.diffdir[i].x + f.irradiance[i].x);
      ASSERT_NEAR(f.composite[i].x, expected, 1e-6f) << i;
      ASSERT_NEAR(f.indirect[i].x, 0.8f * f.irradiance[i].x, 1e-6f) << i;
      if (s.g.normal[i].z > 0.99f) floor_e += f.irradiance[i].x, ++floor_n;
    }
    ASSERT_GT(floor_n, 0u);
    EXPECT_GT(floor_e / double(floor_n), 0.02) << "mean irradiance on the floor";
  }
}

TEST(Temporal, VectorPassOnlyForThePreviousFrame) {
  // Blender's Vector points at frame N−1: with a gap in the frame numbers "auto" scatters.
  Scene s = groove();
  s.g.motion.assign(2 * s.g.pixels(), 0.f);  // a static camera: no motion
  for (const auto& [next, expected] : {std::pair{2, "vector"}, std::pair{3, "scatter"}}) {
    TemporalChain chain(params());
    chain.process(s.g, s.cam, 1, false);
    TemporalReport rep;
    chain.process(s.g, s.cam, next, false, nullptr, &rep);
    EXPECT_EQ(rep.reprojection, expected) << "frame " << next;
    EXPECT_GT(rep.history, 0.99) << "frame " << next;
  }
}

// history_window W: a frame's means reach back 2W − 2 frames at most and W − 1 at least,
// the least where a chain restarts on the next frame.
TEST(Temporal, WindowMemoryIsFinite) {
  EXPECT_EQ(window_memory(0, 7), 0);
  const std::vector<int> two = {window_memory(2, 0), window_memory(2, 1), window_memory(2, 2),
                                window_memory(2, 3)};
  EXPECT_EQ(two, (std::vector<int>{2, 1, 2, 1}));
  for (int w : {2, 5, 6}) {
    int lo = 1 << 20, hi = 0;
    for (int f = -3 * w; f < 3 * w; ++f) {
      lo = std::min(lo, window_memory(w, f));
      hi = std::max(hi, window_memory(w, f));
      if (((f + 1) % (2 * w) + 2 * w) % (2 * w) == 0) EXPECT_EQ(window_memory(w, f), w - 1) << f;
      EXPECT_EQ(window_memory(w, f), window_memory(w, f + 2 * w)) << f;  // periodic
    }
    EXPECT_EQ(lo, w - 1) << w;
    EXPECT_EQ(hi, 2 * w - 2) << w;
  }
}

// With history_window, a chain started window_memory frames before a frame computes that
// frame's ao as a chain over every frame before it does, to the bit; one frame less does not.
// The irradiance (its feedback reaches further back, fading a bounce a frame) comes within
// 1e-3 with 3 frames more, where the exponential blend stays 10x farther (measured: 5.9e-4
// and 0.066, relative RMSE).
TEST(Temporal, AFiniteWindowForgetsWhatIsOlderThanItsMemory) {
  auto frame_of = [](int f) { return groove(1.5 * f); };
  auto run = [&](const Params& p, int from, int to) {
    TemporalChain chain(p);
    AoFrame out;
    for (int f = from; f <= to; ++f) {
      const Scene s = frame_of(f);
      out = chain.process(s.g, s.cam, f, false);
    }
    return out;
  };
  auto rel = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    double d = 0, n = 0;
    for (size_t i = 0; i < a.size(); ++i)
      for (int c = 0; c < 3; ++c) d += std::pow(a[i][c] - b[i][c], 2), n += std::pow(b[i][c], 2);
    return std::sqrt(d / n);
  };
  Params p = params();
  p.history_window = 3;
  const int last = 16;
  const int memory = window_memory(3, last);
  ASSERT_GT(memory, 0);
  const AoFrame whole = run(p, 1, last);
  const AoFrame exact = run(p, last - memory, last);
  const AoFrame short_by_one = run(p, last - memory + 1, last);
  EXPECT_EQ(exact.ao, whole.ao);
  EXPECT_NE(short_by_one.ao, whole.ao);
  const AoFrame settled = run(p, last - memory - 3, last);
  const double window_seam = rel(settled.irradiance, whole.irradiance);
  Params ema = params();
  const double ema_seam =
      rel(run(ema, last - memory - 3, last).irradiance, run(ema, 1, last).irradiance);
  RecordProperty("seams_window_ema", std::to_string(window_seam) + " " + std::to_string(ema_seam));
  EXPECT_LT(window_seam, 1e-3);
  EXPECT_GT(ema_seam, 10 * window_seam);
}

TEST(Temporal, SlicesTurnWithTheFrame) {
  // Frame 0 is the unrotated pattern; other frames turn by a fraction of the spacing.
  float r = 1, j = 1;
  frame_rotation(0, 32, r, j);
  EXPECT_EQ(r, 0.f);
  EXPECT_EQ(j, 0.f);
  frame_rotation(1, 32, r, j);
  EXPECT_NEAR(r, 0.5 * kPi / 32, 1e-6);  // half way between two directions
  frame_rotation(2, 32, r, j);
  EXPECT_NEAR(r, 0.25 * kPi / 32, 1e-6);
  frame_rotation(3, 32, r, j);
  EXPECT_NEAR(r, 0.75 * kPi / 32, 1e-6);
}

// slices "auto": 1 where the run has a temporal chain (its slices rotate from frame to frame
// and accumulate), 2 where it has none; a number is kept. Decided on the whole plan, pre-roll
// included, as the chain is.
TEST(TemporalChain, SlicesAutoIsOneInAChainAndTwoWithout) {
  const std::string shot = test::kRoomPoles + "/frame_####.exr";
  auto slices = [&](const std::string& frames, int preroll, const Params& p) {
    return pipeline::SequenceJob(pipeline::plan_sequence(shot, frames, preroll, ""), p)
        .params()
        .slices;
  };
  EXPECT_EQ(slices("1-4", 0, Params{}), 1);
  EXPECT_EQ(slices("3", 2, Params{}), 1);  // one frame after its pre-roll: a chain
  EXPECT_EQ(slices("1", 0, Params{}), 2);  // one frame: no chain
  EXPECT_EQ(slices("1-4", 0, apply_set(Params{}, "temporal=false")), 2);
  EXPECT_EQ(slices("1-4", 0, apply_set(Params{}, "slices=2")), 2);
  EXPECT_EQ(slices("1", 0, apply_set(Params{}, "slices=4")), 4);
  EXPECT_EQ(apply_set(apply_set(Params{}, "slices=3"), "slices=\"auto\"").slices_auto, true);
}

// With a reduced search (search_scale f > 1) the chain reprojects, fills and blends the
// searched texels (one pixel in f x f) and upsamples their blend once.
Params texel_params() {
  Params p = params();
  p.search_scale = 2;
  return p;
}

// A static camera keeps every texel's history, through either reprojection (the scatter, and
// the Vector pass with zero motion, divided by f): each pixel then holds every frame.
TEST(TemporalTexels, AStaticCameraKeepsEveryTexelsHistory) {
  for (const bool vector : {false, true}) {
    Scene s = groove();
    if (vector) s.g.motion.assign(2 * s.g.pixels(), 0.f);
    Params p = texel_params();
    p.outputs.push_back("history");
    TemporalChain chain(p);
    AoFrame f;
    for (int frame = 1; frame <= 4; ++frame) {
      TemporalReport rep;
      f = chain.process(s.g, s.cam, frame, false, nullptr, &rep);
      if (frame == 1) continue;
      EXPECT_EQ(rep.reprojection, vector ? "vector" : "scatter");
      EXPECT_GT(rep.history, 0.999) << frame;
    }
    ASSERT_EQ(f.history.size(), s.g.pixels());
    size_t geometry = 0, four = 0;
    for (size_t i = 0; i < s.g.pixels(); ++i) {
      if (!(s.g.depth[i] < 1e9f)) continue;
      ++geometry;
      four += std::fabs(f.history[i] - 4.f) < 1e-5f;
    }
    EXPECT_EQ(four, geometry) << (vector ? "vector" : "scatter");
  }
}

// The chain on the texels converges towards the many-bounce result of a search on the same
// texels as closely as the chain on every pixel converges towards the many-bounce result of a
// search on every pixel: what it adds to the reduced search's own error is the chain's lag.
TEST(TemporalTexels, ConvergesAsTheChainOnEveryPixelDoes) {
  const Scene s = groove();
  Params many = params();
  many.bounces = 12;
  const AoFrame ref = compute_ao_frame(s.g, s.cam, many);
  many.search_scale = 2;
  const AoFrame ref_texels = compute_ao_frame(s.g, s.cam, many);
  TemporalChain full(params()), texels(texel_params());
  AoFrame a, b;
  for (int frame = 1; frame <= 40; ++frame) {
    a = full.process(s.g, s.cam, frame, false);
    b = texels.process(s.g, s.cam, frame, false);
  }
  const double err_full = mean_abs_diff(s, a.irradiance, ref.irradiance);
  const double err_texels = mean_abs_diff(s, b.irradiance, ref_texels.irradiance);
  const double reduced_gap = mean_abs_diff(s, ref_texels.irradiance, ref.irradiance);
  RecordProperty("full_texels_reduced_gap", std::to_string(err_full) + " " +
                                                std::to_string(err_texels) + " " +
                                                std::to_string(reduced_gap));
  // Measured: 0.00175 (every pixel), 0.00181 (texels); the 2x2 search of this 96x96 groove
  // is itself 0.0091 from the search on every pixel (its corner is 48 texels across).
  EXPECT_LT(err_texels, 1.25 * err_full);
  EXPECT_LT(mean_abs_diff(s, b.irradiance, ref.irradiance), reduced_gap + 1.25 * err_full);
}

// The texels hold the light that reaches them; each pixel reflects its own share of it
// (diffuse_weight) once, after the upsample: with a metallic pass of 0.5 everywhere and no
// feedback, 0.96 x 0.5 of the irradiance without it.
TEST(TemporalTexels, EachPixelWeighsItsOwnDiffuseShareOnce) {
  Params p = texel_params();
  p.feedback = false;
  TemporalChain a(p), b(p);
  AoFrame fa, fb;
  for (int frame = 1; frame <= 3; ++frame) {
    const Scene turn = groove(2 * frame);
    Scene turned_metal = turn;
    turned_metal.g.metallic.assign(turn.g.pixels(), 0.5f);
    fa = a.process(turn.g, turn.cam, frame, false);
    fb = b.process(turned_metal.g, turned_metal.cam, frame, false);
  }
  double worst = 0, sum = 0;
  for (size_t i = 0; i < fa.irradiance.size(); ++i) {
    worst = std::max(worst, double(std::fabs(fb.irradiance[i].x - 0.48f * fa.irradiance[i].x)));
    sum += fa.irradiance[i].x;
  }
  EXPECT_GT(sum, 1.0);  // there is light to weigh
  EXPECT_LT(worst, 1e-6);
}

// With in-frame bounces the first bounce's occlusion stays on the texels with the last
// bounce's light: ao is that of one bounce to the bit, and the second bounce adds light.
TEST(TemporalTexels, InFrameBouncesKeepTheFirstBouncesOcclusion) {
  Params one = texel_params(), two = texel_params();
  two.bounces = 2;
  TemporalChain a(one), b(two);
  AoFrame fa, fb;
  for (int frame = 1; frame <= 3; ++frame) {
    const Scene s = groove(2 * frame);
    fa = a.process(s.g, s.cam, frame, false);
    fb = b.process(s.g, s.cam, frame, false);
  }
  ASSERT_EQ(fa.ao.size(), fb.ao.size());
  EXPECT_EQ(0, std::memcmp(fa.ao.data(), fb.ao.data(), fa.ao.size() * sizeof(float)));
  double ea = 0, eb = 0;
  for (size_t i = 0; i < fa.irradiance.size(); ++i)
    ea += fa.irradiance[i].x, eb += fb.irradiance[i].x;
  EXPECT_GT(eb, 1.01 * ea);
}

// The same bytes for 1 and 4 threads through a turning camera.
TEST(TemporalTexels, IdenticalBytesForAnyThreadCount) {
  Params p = texel_params();
  p.outputs = {"ao", "bentcone", "irradiance", "history"};
  auto run = [&] {
    TemporalChain chain(p);
    AoFrame f;
    for (int frame = 1; frame <= 3; ++frame) {
      const Scene s = groove(2 * frame);
      f = chain.process(s.g, s.cam, frame, false);
    }
    return f;
  };
  AoFrame one, many;
  tbb::task_arena(1).execute([&] { one = run(); });
  tbb::task_arena(4).execute([&] { many = run(); });
  ASSERT_EQ(one.ao.size(), many.ao.size());
  EXPECT_EQ(0, std::memcmp(one.ao.data(), many.ao.data(), one.ao.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(one.bent.data(), many.bent.data(), one.bent.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(one.irradiance.data(), many.irradiance.data(),
                           one.irradiance.size() * sizeof(Vec3)));
  EXPECT_EQ(
      0, std::memcmp(one.history.data(), many.history.data(), one.history.size() * sizeof(float)));
}

}  // namespace
}  // namespace hbil
