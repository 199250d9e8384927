// march_test.cpp: the vectorised marches (bitmask and horizon) against their scalar references.
//
// march_bitmask_simd.cpp and march_horizon_simd.cpp promise the scalar results to the bit (same
// arithmetic in the same order, lane by lane), so the tolerance here is zero: every float of ao,
// vis, the bent vector and the irradiance must be identical, on analytic scenes with odd sizes
// (partial vectors at the end of a row), with constant and measured thickness, with and without a
// radiance source, interleaved and full resolution, and on a Blender sample.
#include "hbil/march.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cstring>
#include <iostream>
#include <numbers>
#include <string>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"
#include "hbil/interleave.h"
#include "hbil/march_common.h"
#include "io/camera_io.h"
#include "io/exr_frame.h"

namespace hbil {
namespace {

// Bitwise equality of two float arrays, reporting the first difference.
void expect_identical(const float* a, const float* b, size_t n, const char* what) {
  for (size_t i = 0; i < n; ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) {
      ADD_FAILURE() << what << " differs at float " << i << ": " << a[i] << " vs " << b[i];
      return;
    }
}

void expect_identical(const HorizonImage& a, const HorizonImage& b) {
  ASSERT_EQ(a.ao.size(), b.ao.size());
  ASSERT_EQ(a.irradiance.size(), b.irradiance.size());
  expect_identical(a.ao.data(), b.ao.data(), a.ao.size(), "ao");
  expect_identical(a.vis.data(), b.vis.data(), a.vis.size(), "vis");
  expect_identical(&a.bent[0].x, &b.bent[0].x, 3 * a.bent.size(), "bent");
  if (!a.irradiance.empty())
    expect_identical(&a.irradiance[0].x, &b.irradiance[0].x, 3 * a.irradiance.size(), "irradiance");
}

// Both kernels over a view, interleaved and full, with the given radiance (or none).
void compare_kernels(const ViewGBuffer& v, HorizonConfig c, const std::vector<Vec3>* radiance,
                     int slices) {
  for (bool bitmask : {true, false})
    for (bool interleave : {true, false}) {
      SCOPED_TRACE(std::string(bitmask ? "bitmask, " : "horizon, ") +
                   (interleave ? "interleaved" : "full resolution"));
      c.bitmask = bitmask;
      HorizonConfig scalar = c, simd = c;
      scalar.vectorised = false;
      simd.vectorised = true;
      auto run = [&](const HorizonConfig& k) {
        return interleave ? horizon_interleaved(v, k, slices, radiance)
                          : horizon_full(v, k, slices, radiance);
      };
      const HorizonImage a = run(scalar), b = run(simd);
      expect_identical(a, b);
      // The comparison must be able to fail: the scene is occluded somewhere.
      double mean = 0;
      for (float x : a.ao) mean += x;
      EXPECT_LT(mean / double(a.ao.size()), 0.99);
    }
}

GBuffer groove_scene(Camera& cam, int w, int h) {
  cam = test::look_at(w, h, 60, {0.4, 2.0, 1.5}, {0, 0, 0.2});
  std::vector<test::HalfPlane> planes = test::v_groove(75 * std::numbers::pi / 180);
  planes.push_back({{0.3, 0.5, 0.1}, {0.6, 0.0, 0.8}, {0, 0, 1}});
  return test::ray_cast(cam, planes);
}

TEST(MarchSimd, MatchesScalarOnAnalyticSceneWithConstantThickness) {
  for (auto [w, h] : {std::pair{131, 77}, std::pair{64, 48}, std::pair{17, 9}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    Camera cam;
    const GBuffer g = groove_scene(cam, w, h);
    Params p;
    const ViewGBuffer v = make_view_gbuffer(g, cam, p);
    HorizonConfig c = make_horizon_config(p, cam);
    compare_kernels(v, c, nullptr, 2);
    c.thickness = 0.05f;
    c.thickness_growth = 0.02f;
    c.rotation = 0.3f;
    c.jitter_shift = 0.7f;
    compare_kernels(v, c, nullptr, 3);
  }
}

TEST(MarchSimd, MatchesScalarWithMeasuredThicknessAndGather) {
  Camera cam;
  const GBuffer g = groove_scene(cam, 131, 77);
  Params p;
  ViewGBuffer v = make_view_gbuffer(g, cam, p);
  std::vector<Vec3> radiance(v.pixels());
  v.thickness.assign(v.pixels(), -1.f);
  for (size_t i = 0; i < v.pixels(); ++i) {
    radiance[i] = Vec3{float(i % 7), float(i % 5), 1.f};
    if (i % 3) v.thickness[i] = 0.01f * float(i % 11);
  }
  HorizonConfig c = make_horizon_config(p, cam);
  ASSERT_GT(c.gather_steps, 0);
  compare_kernels(v, c, &radiance, 2);
  c.gather_thickness = 1.3f;  // the gather-only samples thicker than the others
  compare_kernels(v, c, &radiance, 2);
  c.gather_steps = 0;  // the gather within the AO radius only
  compare_kernels(v, c, &radiance, 2);
  // Radiance in the directions the gather finds empty (unseen_radiance).
  c = make_horizon_config(p, cam);
  c.fill = Vec3{0.3f, 0.2f, 0.1f};
  compare_kernels(v, c, &radiance, 2);
  for (bool bitmask : {true, false}) {
    c.bitmask = bitmask;
    HorizonConfig none = c;
    none.fill = Vec3{};
    const HorizonImage lit = horizon_interleaved(v, c, 2, &radiance),
                       unlit = horizon_interleaved(v, none, 2, &radiance);
    double more = 0;
    for (size_t i = 0; i < v.pixels(); ++i) more += lit.irradiance[i].z - unlit.irradiance[i].z;
    EXPECT_GT(more / double(v.pixels()), 0.01)
        << (bitmask ? "bitmask" : "horizon") << ": the fill must light the open directions";
  }
}

// A floor seen almost edge-on, from 4 cm above it, with a wall across it: many rays through
// the steps graze the samples' surfaces (the cosine under march::kGrazing), where the step
// keeps the sample's own position instead of moving it onto the ray (march_common.h).
TEST(MarchSimd, MatchesScalarWhereTheRayGrazesTheSample) {
  Camera cam = test::look_at(96, 64, 50, {0.0, 2.5, 0.04}, {0.1, 0, 0.02});
  std::vector<test::HalfPlane> planes = test::v_groove(80 * std::numbers::pi / 180);
  planes.push_back({{0.3, 0.8, 0}, {-0.9, 0.0, 0.44}, {0, 0, 1}});
  const GBuffer g = test::ray_cast(cam, planes);
  Params p;
  const ViewGBuffer v = make_view_gbuffer(g, cam, p);
  // The scene must reach the grazing case: texels whose surface the view ray meets under
  // less than 3 degrees (236 of them).
  size_t grazing = 0;
  for (size_t i = 0; i < v.pixels(); ++i) {
    if (v.is_background(i)) continue;
    const Vec3 P = v.position[i];
    if (std::abs(dot(P, v.normal[i])) < 0.05f * std::sqrt(dot(P, P))) ++grazing;
  }
  EXPECT_GT(grazing, 150u);
  std::vector<Vec3> radiance(v.pixels());
  for (size_t i = 0; i < v.pixels(); ++i) radiance[i] = Vec3{float(i % 7), float(i % 5), 1.f};
  compare_kernels(v, make_horizon_config(p, cam), &radiance, 2);
  compare_kernels(v, make_horizon_config(p, cam), nullptr, 3);
}

// Texels behind the camera and at its centre (a depth pass with bad pixels gives them): their
// radius in texels is negative, and just behind the camera, their gather-only steps' offsets
// are far beyond any view, which both marches clamp before rounding to an integer; they must
// agree there too, and not read outside the view (ASan).
TEST(MarchSimd, MatchesScalarWhereTexelsLieBehindTheCamera) {
  Camera cam;
  const GBuffer g = groove_scene(cam, 67, 41);
  Params p;
  ViewGBuffer v = make_view_gbuffer(g, cam, p);
  size_t odd = 0;
  for (size_t i = 0; i < v.pixels(); i += 7) {
    if (v.is_background(i)) continue;
    const float scale[3] = {-1.f, -1e-30f, 0.f};  // behind; just behind; at the centre
    v.position[i] = v.position[i] * scale[i % 3];
    ++odd;
  }
  ASSERT_GT(odd, 200u);
  std::vector<Vec3> radiance(v.pixels(), Vec3{0.5f, 0.25f, 1.f});
  compare_kernels(v, make_horizon_config(p, cam), &radiance, 2);
  compare_kernels(v, make_horizon_config(p, cam), nullptr, 3);
}

// samples/room_poles frame 3 as the search sees it.
struct Sample {
  GBuffer g;
  Camera cam;
  ViewGBuffer v;
};
Sample room_poles_frame3(const Params& p) {
  const std::string path = std::string(HBIL_SOURCE_DIR) + "/samples/room_poles/frame_0003.exr";
  const io::InputFrame in = io::open_frame(path, 3, p);
  Sample s;
  s.g = io::read_fields(in, io::fields_needed(in, p), p);
  s.cam = io::find_camera(in, s.g, p);
  s.v = make_view_gbuffer(s.g, s.cam, p);
  return s;
}

TEST(MarchSimd, MatchesScalarOnBlenderSample) {
  const Params p;
  const Sample sample = room_poles_frame3(p);
  const GBuffer& g = sample.g;
  const Camera& cam = sample.cam;
  const ViewGBuffer& v = sample.v;
  ASSERT_FALSE(v.thickness.empty()) << "the sample lost its back-face layer";
  std::vector<Vec3> radiance(g.pixels());
  for (size_t i = 0; i < g.pixels(); ++i)
    radiance[i] = Vec3{g.diffcol[i].x * g.diffdir[i].x, g.diffcol[i].y * g.diffdir[i].y,
                       g.diffcol[i].z * g.diffdir[i].z};
  compare_kernels(v, make_horizon_config(p, cam), &radiance, 2);
  // Without it, the thickness from each object's extent (thickness_extent): some texels have
  // one, some say nothing (the constant).
  const Params no_back = apply_set(p, "passes.backdepth=\"\"");
  const Sample plain = room_poles_frame3(no_back);
  size_t bounded = 0, open = 0;
  for (size_t i = 0; i < plain.v.pixels(); ++i) {
    if (plain.v.is_background(i)) continue;
    plain.v.thickness[i] < 0.f ? ++open : ++bounded;
  }
  EXPECT_GT(bounded, 1000u);
  EXPECT_GT(open, 1000u);
  compare_kernels(plain.v, make_horizon_config(no_back, cam), &radiance, 2);
}

// Every instruction set the machine has gives the same bits (so do frames computed on farm
// nodes with different processors).
TEST(MarchSimd, EveryInstructionSetGivesTheSameBits) {
  const Params p;
  const Sample sample = room_poles_frame3(p);
  std::vector<Vec3> radiance(sample.g.pixels());
  for (size_t i = 0; i < radiance.size(); ++i) radiance[i] = sample.g.diffdir[i];
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  ASSERT_FALSE(targets.empty());
  std::cout << "instruction sets:";
  for (std::int64_t t : targets) {
    SCOPED_TRACE(hwy::TargetName(t));
    std::cout << " " << hwy::TargetName(t);
    hwy::SetSupportedTargetsForTest(t);
    EXPECT_STREQ(march_simd_target(), hwy::TargetName(t));
    HorizonConfig c = make_horizon_config(p, sample.cam);
    compare_kernels(sample.v, c, &radiance, 2);
    c.fill = Vec3{0.05f, 0.1f, 0.15f};  // unseen_radiance
    compare_kernels(sample.v, c, &radiance, 2);
    // Without the back-face layer: the thickness from each object's extent.
    ViewGBuffer bounded = sample.v;
    thickness_from_extent(bounded, sample.cam, float(p.depth_tolerance), float(p.thickness));
    compare_kernels(bounded, make_horizon_config(p, sample.cam), &radiance, 2);
  }
  std::cout << "\n";
  hwy::SetSupportedTargetsForTest(0);
}

// A later bounce summed from the first one's recorded gather equals a new search with its
// radiance, to the bit, with both marches.
// The bitmask march's γ = atan2(n'x, n'y) is march::fast_atan2 (the vector march repeats it lane by
// lane): against atan2 in double all around the circle, at lengths from 1e-30 to 1e30, within the
// 4e-7 rad its comment states; on the axes and at the origin as stated.
TEST(FastAtan2, WithinFourTenthsOfAMicroradianAllAroundTheCircle) {
  constexpr double kPi = std::numbers::pi;
  double worst = 0;
  for (int k = 0; k < 100000; ++k) {
    const double t = -kPi + 2 * kPi * (k + 0.5) / 100000;
    for (double r : {1e-30, 1e-3, 1.0, 7.5, 1e30}) {
      const float y = float(r * std::sin(t)), x = float(r * std::cos(t));
      const double want = std::atan2(double(y), double(x));
      worst = std::max(worst, std::abs(double(march::fast_atan2(y, x)) - want));
    }
  }
  std::cout << "fast_atan2: largest error " << worst << " rad\n";
  EXPECT_LT(worst, 4e-7);
  EXPECT_EQ(march::fast_atan2(0.f, 0.f), 0.f);
  EXPECT_EQ(march::fast_atan2(0.f, 2.f), 0.f);
  EXPECT_NEAR(march::fast_atan2(2.f, 0.f), 0.5 * kPi, 1e-7);
  EXPECT_NEAR(march::fast_atan2(-2.f, 0.f), -0.5 * kPi, 1e-7);
  EXPECT_NEAR(march::fast_atan2(0.f, -2.f), kPi, 1e-7);
  EXPECT_NEAR(march::fast_atan2(1.f, 1.f), 0.25 * kPi, 1e-7);
}

TEST(GatherRecord, ReplayEqualsANewSearch) {
  const Params p;
  const Sample sample = room_poles_frame3(p);
  const GBuffer& g = sample.g;
  const Camera& cam = sample.cam;
  const ViewGBuffer& v = sample.v;
  std::vector<Vec3> first(g.pixels()), second(g.pixels());
  for (size_t i = 0; i < g.pixels(); ++i) {
    first[i] = g.diffdir[i];
    second[i] = Vec3{float(i % 7) * 0.1f, g.diffcol[i].y, 1.f};
  }
  for (bool simd : {true, false}) {
    SCOPED_TRACE(simd ? "SIMD" : "scalar");
    HorizonConfig c = make_horizon_config(p, cam);
    c.vectorised = simd;
    GatherRecord record;
    const HorizonImage a = horizon_interleaved(v, c, 2, &first, true, &record);
    ASSERT_TRUE(record.filled);
    size_t entries = 0;
    for (const GatherLog& l : record.rows) entries += l.entries.size();
    EXPECT_GT(entries, g.pixels()) << "the gather was not logged";
    expect_identical(a, horizon_interleaved(v, c, 2, &first));
    const HorizonImage replayed = horizon_interleaved(v, c, 2, &second, true, &record);
    const HorizonImage marched = horizon_interleaved(v, c, 2, &second);
    expect_identical(replayed, marched);
    // With radiance in the open directions, recorded with one value and replayed with another.
    HorizonConfig lit = c;
    lit.fill = Vec3{0.1f, 0.2f, 0.3f};
    GatherRecord lit_record;
    expect_identical(horizon_interleaved(v, lit, 2, &first, true, &lit_record),
                     horizon_interleaved(v, lit, 2, &first));
    lit.fill = Vec3{0.4f, 0.f, 0.05f};
    expect_identical(horizon_interleaved(v, lit, 2, &second, true, &lit_record),
                     horizon_interleaved(v, lit, 2, &second));
    double diff = 0;
    for (size_t i = 0; i < g.pixels(); ++i)
      diff += std::fabs(a.irradiance[i].x - marched.irradiance[i].x);
    EXPECT_GT(diff, 1.0) << "the two radiances must give different light";
  }
}

// Later in-frame bounces share the first one's occlusion: with 3 bounces the search gives the
// ao, vis and bent of one bounce to the bit, and more light.
TEST(GatherRecord, LaterBouncesKeepTheFirstOcclusion) {
  Params p;
  p.outputs = {"ao", "bentcone", "irradiance"};
  const Sample s = room_poles_frame3(p);
  for (bool vectorised : {true, false}) {
    SCOPED_TRACE(vectorised ? "SIMD" : "scalar");
    p.vectorised = vectorised;
    p.bounces = 1;
    const HorizonImage one = search_frame(s.v, s.g, s.cam, p, FrameInputs{});
    p.bounces = 3;
    const HorizonImage three = search_frame(s.v, s.g, s.cam, p, FrameInputs{});
    ASSERT_EQ(three.ao.size(), one.ao.size());
    EXPECT_EQ(std::memcmp(three.ao.data(), one.ao.data(), one.ao.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(three.vis.data(), one.vis.data(), one.vis.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(three.bent.data(), one.bent.data(), one.bent.size() * sizeof(Vec3)), 0);
    double e1 = 0, e3 = 0;
    for (size_t i = 0; i < one.irradiance.size(); ++i)
      e1 += one.irradiance[i].y, e3 += three.irradiance[i].y;
    EXPECT_GT(e3, 1.05 * e1) << "the later bounces add light";
  }
}

}  // namespace
}  // namespace hbil
