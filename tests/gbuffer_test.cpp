// gbuffer_test.cpp: the view-space G-buffer (gbuffer.h): pixels with a zero-length normal
// are found, and are taken for background by the whole chain.
#include "hbil/gbuffer.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"
#include "test_util.h"

namespace hbil {
namespace {

// The busy scene with colour passes, so that every output layer is computed.
GBuffer lit_scene(Camera& cam) {
  GBuffer g = test::busy_scene(cam);
  g.diffcol.assign(g.pixels(), Vec3{0.8f, 0.5f, 0.2f});
  g.diffdir.assign(g.pixels(), Vec3{1, 1, 1});
  return g;
}

// A block of geometry pixels, [x0, x0 + 6) x [y0, y0 + 4).
constexpr int kX0 = 60, kY0 = 40, kBw = 6, kBh = 4;

template <typename F>
void for_block(const GBuffer& g, F&& f) {
  for (int y = kY0; y < kY0 + kBh; ++y)
    for (int x = kX0; x < kX0 + kBw; ++x) f(size_t(y) * g.width + x);
}

TEST(ZeroNormals, AreFoundOnGeometryOnly) {
  Camera cam;
  GBuffer g = lit_scene(cam);
  // Blender's background already has zero normals: none of them counts.
  EXPECT_EQ(find_zero_normals(g, Params{}).count, 0u);
  for_block(g, [&](size_t i) {
    ASSERT_LT(g.depth[i], 1e9f) << "the block must be on geometry";
    g.normal[i] = Vec3{};
  });
  const ZeroNormals z = find_zero_normals(g, Params{});
  EXPECT_EQ(z.count, size_t(kBw * kBh));
  EXPECT_EQ(z.first, size_t(kY0) * g.width + kX0);
  // Covered by alpha 0: background whatever the normal.
  g.alpha.assign(g.pixels(), 1.f);
  for_block(g, [&](size_t i) { g.alpha[i] = 0; });
  EXPECT_EQ(find_zero_normals(g, Params{}).count, 0u);
}

// A zero normal neither receives nor occludes: the frame is computed exactly as if those
// pixels were background (depth 1e10), and every output stays finite.
TEST(ZeroNormals, AreBackgroundForTheSearch) {
  Camera cam;
  GBuffer zero = lit_scene(cam);
  for_block(zero, [&](size_t i) { zero.normal[i] = Vec3{}; });
  GBuffer background = zero;
  for_block(background, [&](size_t i) { background.depth[i] = 1e10f; });
  Params p;
  p.outputs = {"ao", "bentcone", "irradiance", "indirect", "composite"};
  const AoFrame a = compute_ao_frame(zero, cam, p), b = compute_ao_frame(background, cam, p);
  test::expect_same_layers(a, b, {"ao", "bent", "cone_cos", "irradiance", "indirect", "composite"});
  // With its normals intact the block occludes and lights its neighbours: pixels outside
  // it change, so the equality above is not that of a block the search never reads.
  const AoFrame intact = compute_ao_frame(lit_scene(cam), cam, p);
  std::vector<bool> in_block(a.ao.size(), false);
  for_block(zero, [&](size_t i) { in_block[i] = true; });
  size_t changed = 0;
  for (size_t i = 0; i < a.ao.size(); ++i)
    changed +=
        !in_block[i] && (intact.ao[i] != a.ao[i] || intact.irradiance[i].x != a.irradiance[i].x);
  EXPECT_GT(changed, 10u) << "pixels outside the block that the block's geometry affects";
  for (size_t i = 0; i < a.ao.size(); ++i) {
    ASSERT_TRUE(std::isfinite(a.ao[i]) && std::isfinite(a.cone_cos[i])) << i;
    ASSERT_TRUE(std::isfinite(a.bent[i].x) && std::isfinite(a.bent[i].y) &&
                std::isfinite(a.bent[i].z))
        << i;
    ASSERT_TRUE(std::isfinite(a.irradiance[i].x) && std::isfinite(a.composite[i].x)) << i;
  }
  // As background: AO 1 and a full cone at the block itself.
  for_block(zero, [&](size_t i) {
    EXPECT_EQ(a.ao[i], 1.f);
    EXPECT_EQ(a.cone_cos[i], 0.f);
  });
}

// A bar 4 pixels tall across the whole frame, at depth 5, in front of a wall at depth 10:
// the bar's pixels take its height (4 pixels x 5 / 50 px focal = 0.4 world units: its
// horizontal runs reach the image's edges), the wall says nothing (every run of it reaches an
// edge: -1), and the 6 rows of a tilted floor (above a strip at depth 2) are one run however
// much its depth changes from row to row, up to the largest thickness given (1.5).
TEST(ViewGBuffer, SimdRowsGiveTheScalarBufferToTheBit) {
  // The busy scene with a back-face depth, made awkward on purpose: zero, NaN, infinite and
  // short normals, depths at and past the background, back faces in front of, just behind and
  // far behind the front, zero and NaN coverage; a width that is no multiple of any vector
  // length.
  Camera cam;
  GBuffer g = test::busy_scene(cam);
  std::uint32_t state = 99;
  auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 8; };
  g.backdepth.resize(g.pixels());
  g.alpha.assign(g.pixels(), 1.f);
  for (size_t i = 0; i < g.pixels(); ++i) {
    const float z = g.depth[i];
    g.backdepth[i] = z + float(next() % 1000) * 1e-3f - 0.1f;
    switch (next() % 30) {
      case 0:
        g.normal[i] = Vec3{};
        break;
      case 1:
        g.normal[i].y = std::nanf("");
        break;
      case 2:
        g.normal[i].x = HUGE_VALF;
        break;
      case 3:
        g.normal[i] = g.normal[i] * 0.25f;
        break;
      case 4:
        g.depth[i] = 1e10f;
        break;
      case 5:
        g.depth[i] = std::nanf("");
        break;
      case 6:
        g.alpha[i] = 0.f;
        break;
      case 7:
        g.alpha[i] = std::nanf("");
        break;
      case 8:
        g.backdepth[i] = z * 1.001f;
        break;
      case 9:
        g.backdepth[i] = 1e10f;
        break;
      default:
        break;
    }
  }
  for (int w : {g.width, g.width - 3}) {
    GBuffer c = g;
    if (w != g.width) {  // the first w columns
      auto crop = [&](auto& field) {
        auto out = field;
        out.clear();
        for (int y = 0; y < g.height; ++y)
          for (int x = 0; x < w; ++x) out.push_back(field[size_t(y) * g.width + x]);
        field = out;
      };
      crop(c.depth), crop(c.backdepth), crop(c.normal), crop(c.alpha);
      c.width = w;
    }
    Params p;
    p.vectorised = false;
    const ViewGBuffer a = make_view_gbuffer(c, cam, p);
    p.vectorised = true;
    // Every instruction set the machine has.
    for (std::int64_t t : hwy::SupportedAndGeneratedTargets()) {
      SCOPED_TRACE(hwy::TargetName(t));
      hwy::SetSupportedTargetsForTest(t);
      const ViewGBuffer b = make_view_gbuffer(c, cam, p);
      ASSERT_EQ(a.position.size(), b.position.size());
      ASSERT_EQ(a.thickness.size(), b.thickness.size());
      EXPECT_EQ(std::memcmp(a.position.data(), b.position.data(), a.position.size() * 12), 0) << w;
      EXPECT_EQ(std::memcmp(a.normal.data(), b.normal.data(), a.normal.size() * 12), 0) << w;
      EXPECT_EQ(std::memcmp(a.thickness.data(), b.thickness.data(), a.thickness.size() * 4), 0)
          << w;
    }
    hwy::SetSupportedTargetsForTest(0);
    // Not vacuous: geometry, background and measured thickness all occur.
    size_t geometry = 0, thick = 0;
    for (size_t i = 0; i < a.pixels(); ++i)
      geometry += !a.is_background(i), thick += a.thickness[i] >= 0.f;
    EXPECT_GT(geometry, a.pixels() / 2);
    EXPECT_LT(geometry, a.pixels());
    EXPECT_GT(thick, geometry / 2);
  }
}

TEST(ThicknessExtent, BoundsEachPixelByTheSmallerRunOfItsSurface) {
  constexpr int kW = 64, kH = 32;
  Camera cam;
  cam.width = kW, cam.height = kH, cam.fx = cam.fy = 50, cam.cx = kW / 2.0, cam.cy = kH / 2.0;
  ViewGBuffer v;
  v.width = kW, v.height = kH;
  v.position.resize(v.pixels());
  v.normal.resize(v.pixels());
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      const bool bar = y >= 10 && y < 14, floor = y >= 24 && y < 30, strip = y >= 30;
      // The floor: z grows 5 % a row (a plane seen at a grazing angle).
      const double z = bar ? 5.0 : floor ? 12.0 * std::pow(1.05, y - 24) : strip ? 2.0 : 10.0;
      v.position[i] = Vec3(cam.unproject(x + 0.5, y + 0.5, z));
      v.normal[i] =
          floor
              ? normalize_or_zero(cross(
                    v.position[i] - Vec3(cam.unproject(x + 0.5, y - 0.5, z / 1.05)), Vec3{1, 0, 0}))
              : Vec3{0, 0, -1};
    }
  thickness_from_extent(v, cam, 0.05f, 1.5f);
  ASSERT_EQ(v.thickness.size(), v.pixels());
  for (int x = 0; x < kW; ++x) {
    EXPECT_NEAR(v.thickness[size_t(12) * kW + x], 0.4f, 1e-6) << x;  // the bar
    EXPECT_EQ(v.thickness[size_t(5) * kW + x], -1.f) << x;           // the wall above it
    const size_t f = size_t(24) * kW + x;  // the floor's first row: 6 rows at depth 12
    EXPECT_NEAR(v.thickness[f], 6 * 12.0 / 50, 1e-5) << x;
    EXPECT_EQ(v.thickness[size_t(29) * kW + x], 1.5f) << x;  // its last, farther: at most 1.5
  }
}

}  // namespace
}  // namespace hbil
