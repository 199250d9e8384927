// reduced_test.cpp: the reduced-resolution search (reduced.h, Params::search_scale): the
// reduced buffer is the full one on a coarser grid, the upsample never mixes surfaces, the
// radiance block mean stays on the texel's surface, and a reduced search keeps the closed
// forms of the V-groove.
#include "hbil/reduced.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"
#include "test_util.h"

namespace hbil {
namespace {

constexpr double kPi = std::numbers::pi;

// Two fronto-parallel planes, x < split at depth 2 and the rest at depth 5; normals +z
// towards the camera (view space: z forward, so the normal is (0, 0, -1)).
ViewGBuffer two_planes(int w, int h, int split) {
  ViewGBuffer v;
  v.width = w;
  v.height = h;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float z = x < split ? 2.f : 5.f;
      v.position.push_back(Vec3{(x - w / 2.f) * z / 100.f, (y - h / 2.f) * z / 100.f, z});
      v.normal.push_back(Vec3{0, 0, -1});
    }
  return v;
}

TEST(ReducedSearch, AutoKeeps540PixelsAcrossTheShorterSide) {
  Params p;  // the default is auto
  EXPECT_EQ(effective_search_scale(p, 256, 144), 1);
  EXPECT_EQ(effective_search_scale(p, 1280, 720), 1);
  EXPECT_EQ(effective_search_scale(p, 1920, 1079), 1);
  EXPECT_EQ(effective_search_scale(p, 1920, 1080), 2);
  EXPECT_EQ(effective_search_scale(p, 1080, 1920), 2);  // portrait
  EXPECT_EQ(effective_search_scale(p, 3840, 2160), 4);
  p.search_scale = 3;
  EXPECT_EQ(effective_search_scale(p, 256, 144), 3);
}

TEST(ReducedSearch, TexelIsThePixelOnACoarserGrid) {
  const ViewGBuffer v = two_planes(13, 7, 5);
  const ViewGBuffer lo = reduce_view(v, 2);
  EXPECT_EQ(lo.width, 7);  // ceil(13 / 2)
  EXPECT_EQ(lo.height, 4);
  EXPECT_EQ(lo.scale, 2);
  for (int j = 0; j < lo.height; ++j)
    for (int i = 0; i < lo.width; ++i) {
      const size_t k = size_t(j) * lo.width + i, p = size_t(2 * j) * v.width + 2 * i;
      EXPECT_EQ(0, std::memcmp(&lo.position[k], &v.position[p], sizeof(Vec3)));
      EXPECT_EQ(0, std::memcmp(&lo.normal[k], &v.normal[p], sizeof(Vec3)));
    }
  EXPECT_EQ(reduce_view(lo, 3).scale, 6);
}

TEST(ReducedSearch, RadianceBlockMeanStaysOnItsSurface) {
  // Texel 2 of the row covers pixels 4 and 5 (x = 4 on the near plane, x = 5 on the far one).
  const ViewGBuffer v = two_planes(8, 2, 5);
  std::vector<Vec3> L(v.pixels());
  for (size_t i = 0; i < L.size(); ++i) L[i] = Vec3{float(i % 8), 1, 0};
  const ViewGBuffer lo = reduce_view(v, 2);
  const std::vector<Vec3> r = reduce_radiance(v, lo, 2, L, 0.05f);
  EXPECT_FLOAT_EQ(r[0].x, 0.5f);  // pixels 0, 1 (both rows): mean 0.5
  EXPECT_FLOAT_EQ(r[2].x, 4.f);   // only pixel 4 is on the texel's plane
  EXPECT_FLOAT_EQ(r[3].x, 6.5f);
  EXPECT_FLOAT_EQ(r[2].y, 1.f);
}

TEST(ReducedSearch, ADegenerateNormalKeepsItsOwnPixelsRadiance) {
  // A texel whose normal is zero (or NaN) fails even its own pixel's same-surface test: it
  // takes its own pixel's radiance, not 0 / 0.
  ViewGBuffer v = two_planes(8, 2, 5);
  v.normal[2] = Vec3{0, 0, 0};
  v.normal[6] = Vec3{std::nanf(""), 0, 0};
  std::vector<Vec3> L(v.pixels());
  for (size_t i = 0; i < L.size(); ++i) L[i] = Vec3{float(i % 8), 1, 0};
  const ViewGBuffer lo = reduce_view(v, 2);
  const std::vector<Vec3> r = reduce_radiance(v, lo, 2, L, 0.05f);
  EXPECT_EQ(r[1].x, 2.f);
  EXPECT_EQ(r[3].x, 6.f);
  EXPECT_FLOAT_EQ(r[0].x, 0.5f);  // the others as before
  for (const Vec3& x : r) EXPECT_TRUE(std::isfinite(x.x) && std::isfinite(x.y)) << x.x;
}

TEST(ReducedSearch, UpsampleNeverMixesSurfaces) {
  // Texel values: 0.25 on the near plane, 0.75 on the far one. Every full-resolution pixel
  // must get exactly its own plane's value, also at the edge (x = 9 is far, texel 4 = pixel 8
  // near, texel 5 = pixel 10 far).
  const ViewGBuffer v = two_planes(21, 9, 9);
  const ViewGBuffer lo = reduce_view(v, 2);
  HorizonImage h;
  h.width = lo.width;
  h.height = lo.height;
  for (size_t k = 0; k < lo.pixels(); ++k) {
    const float a = lo.position[k].z < 3 ? 0.25f : 0.75f;
    h.ao.push_back(a);
    h.vis.push_back(a);
    h.bent.push_back(Vec3{0, 0, -a});
    h.irradiance.push_back(Vec3{a, a, a});
  }
  const HorizonImage up = upsample_horizon(v, lo, 2, h, 0.05f);
  ASSERT_EQ(up.ao.size(), v.pixels());
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x) {
      const size_t p = size_t(y) * v.width + x;
      const float a = x < 9 ? 0.25f : 0.75f;
      EXPECT_FLOAT_EQ(up.ao[p], a) << x << "," << y;
      EXPECT_FLOAT_EQ(up.vis[p], a);
      EXPECT_FLOAT_EQ(up.bent[p].z, -a);
      EXPECT_FLOAT_EQ(up.irradiance[p].y, a);
    }
}

// A search result on lo with a different value in every field of neighbouring texels.
HorizonImage texel_pattern(const ViewGBuffer& lo) {
  HorizonImage h;
  h.width = lo.width;
  h.height = lo.height;
  for (size_t k = 0; k < lo.pixels(); ++k) {
    const float a = 0.03f * float(k % 13);
    h.ao.push_back(a);
    h.vis.push_back(a);
    h.bent.push_back(Vec3{0, 0, -a});
    h.irradiance.push_back(Vec3{a, 2 * a, 0.5f - a});
  }
  return h;
}
// Its irradiance alone (a later bounce's).
HorizonImage irradiance_of(const HorizonImage& h) {
  HorizonImage alone;
  alone.width = h.width;
  alone.height = h.height;
  alone.irradiance = h.irradiance;
  return alone;
}

TEST(ReducedSearch, TheIrradianceAloneIsUpsampledToTheSameBits) {
  // A later in-frame bounce upsamples its irradiance alone: the same values as the whole
  // result's, on rough surfaces where some pixels fall back to their nearest texel.
  ViewGBuffer v = two_planes(23, 11, 9);
  for (size_t p = 0; p < v.pixels(); ++p) v.position[p].z += 0.01f * float((p * 7) % 5);
  const ViewGBuffer lo = reduce_view(v, 2);
  const HorizonImage h = texel_pattern(lo);
  const HorizonImage whole = upsample_horizon(v, lo, 2, h, 0.05f);
  const HorizonImage alone = irradiance_of(h);
  const HorizonImage up = upsample_horizon(v, lo, 2, alone, 0.05f);
  EXPECT_TRUE(up.ao.empty() && up.vis.empty() && up.bent.empty());
  ASSERT_EQ(up.irradiance.size(), v.pixels());
  size_t lit = 0;
  for (size_t p = 0; p < v.pixels(); ++p) {
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(std::bit_cast<std::uint32_t>((&up.irradiance[p].x)[c]),
                std::bit_cast<std::uint32_t>((&whole.irradiance[p].x)[c]))
          << p;
    lit += up.irradiance[p].y > 0.f;
  }
  EXPECT_GT(lit, v.pixels() / 2);
}

// The later bounces upsample by a plan made once (plan_upsample): the direct upsample's bits,
// for the whole result and the irradiance alone, at scales 2 and 3, with pixels that take the
// bilinear texels, pixels that fall back to their nearest texel, and background.
TEST(ReducedSearch, AnUpsamplePlanGivesTheSameBits) {
  ViewGBuffer v = two_planes(23, 11, 9);
  for (size_t p = 0; p < v.pixels(); ++p) v.position[p].z += 0.01f * float((p * 7) % 5);
  v.position[5] = Vec3{0, 0, ViewGBuffer::kBackground * 2};
  v.normal[5] = Vec3{};
  // Pixels (5, 5) and (7, 7), no texel at scale 2 or 3, far in front of their neighbours: no
  // texel around them is on their surface.
  for (size_t p : {size_t(5 * 23 + 5), size_t(7 * 23 + 7)}) v.position[p] = v.position[p] * 0.5f;
  for (int f : {2, 3}) {
    const ViewGBuffer lo = reduce_view(v, f);
    const HorizonImage h = texel_pattern(lo), alone = irradiance_of(h);
    const UpsamplePlan plan = plan_upsample(v, lo, f, 0.05f);
    size_t bilinear = 0, nearest = 0, none = 0;
    for (std::uint32_t c : plan.choice)
      (c == UpsamplePlan::kNone ? none : c & UpsamplePlan::kBilinear ? bilinear : nearest)++;
    EXPECT_GT(bilinear, v.pixels() / 2) << f;
    EXPECT_GT(nearest, 0u) << f;
    EXPECT_GT(none, 0u) << f;
    for (const HorizonImage* in : {&h, &alone}) {
      SCOPED_TRACE(std::to_string(f) + (in == &h ? " whole" : " irradiance alone"));
      const HorizonImage direct = upsample_horizon(v, lo, f, *in, 0.05f);
      const HorizonImage planned = upsample_horizon(v, lo, plan, *in);
      test::expect_same_bytes(direct.irradiance, planned.irradiance, "irradiance");
      if (in == &alone) {
        EXPECT_TRUE(planned.ao.empty() && planned.vis.empty() && planned.bent.empty());
        continue;
      }
      test::expect_same_bytes(direct.ao, planned.ao, "ao");
      test::expect_same_bytes(direct.vis, planned.vis, "vis");
      test::expect_same_bytes(direct.bent, planned.bent, "bent");
    }
  }
}

TEST(ReducedSearch, UpsampleOfASmoothFieldIsBilinear) {
  const ViewGBuffer v = two_planes(16, 8, 100);  // one plane
  const ViewGBuffer lo = reduce_view(v, 2);
  HorizonImage h;
  h.width = lo.width;
  h.height = lo.height;
  for (int j = 0; j < lo.height; ++j)
    for (int i = 0; i < lo.width; ++i) {
      h.ao.push_back(0.01f * float(i) + 0.1f * float(j));
      h.vis.push_back(1.f);
      h.bent.push_back(Vec3{});
    }
  const HorizonImage up = upsample_horizon(v, lo, 2, h, 0.05f);
  for (int y = 0; y < v.height - 1; ++y)
    for (int x = 0; x < v.width - 1; ++x)  // the last row and column extrapolate
      EXPECT_NEAR(up.ao[size_t(y) * v.width + x], 0.005f * x + 0.05f * y, 1e-6) << x << "," << y;
}

// A count (the chain's history length) keeps whole numbers: each pixel takes the texel it
// weighs most, here on two planes: (x, y) takes texel (x / 2, y / 2) (a tie of weights goes
// to the first), except where that texel lies on the other plane.
TEST(ReducedSearch, ACountIsUpsampledToTheTexelWeighedMost) {
  ViewGBuffer v = two_planes(12, 6, 5);
  v.position[size_t(5) * v.width + 11].z = ViewGBuffer::kBackground;  // one background pixel
  const ViewGBuffer lo = reduce_view(v, 2);
  std::vector<float> count(lo.pixels());
  for (size_t k = 0; k < count.size(); ++k) count[k] = float(k + 1);
  const UpsamplePlan plan = plan_upsample(v, lo, 2, 0.05f);
  const std::vector<float> up = upsample_count(v, lo, plan, count);
  ASSERT_EQ(up.size(), v.pixels());
  EXPECT_EQ(up[size_t(5) * v.width + 11], 0.f);
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x) {
      if (y == 5 && x == 11) continue;
      // x = 5 is on the far plane, its texel (x = 4) on the near one: it takes texel x = 6.
      const int i = x == 5 ? 3 : x / 2, j = y / 2;
      EXPECT_EQ(up[size_t(y) * v.width + x], count[size_t(j) * lo.width + i]) << x << "," << y;
    }
}

// The 90-degree V-groove of horizon_test.cpp, searched on every second pixel: AO and the cone
// keep the closed forms within the bounds of the full-resolution search.
TEST(ReducedSearch, GrooveKeepsTheClosedForm) {
  const double gamma = 90 * kPi / 180, L = 1.0;
  const Vec3d bisector{0, std::cos(gamma / 2), std::sin(gamma / 2)};
  const Camera cam = test::look_at(192, 192, 90, bisector * 2.5, bisector * 0.4);
  const GBuffer g = test::ray_cast(cam, test::v_groove(gamma, L));
  Params p;
  p.method = "horizon";
  p.interleave = false;
  p.slices = 32;
  p.steps = 96;
  p.radius = 1e3;
  p.search_scale = 2;
  const AoFrame f = compute_ao_frame(g, cam, p);
  int checked = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const size_t i = size_t(y) * g.width + x;
      if (g.normal[i].z < 0.99f) continue;
      const Vec3d hit = cam.view_to_world(cam.unproject(x + 0.5, y + 0.5, g.depth[i]));
      const double d = hit.y;
      if (d < 0.05 || d > 0.6 || std::fabs(hit.x) > 0.3) continue;
      const double psi = std::atan2(L * std::sin(gamma), d - L * std::cos(gamma));
      ++checked;
      EXPECT_NEAR(f.ao[i], (1 + std::cos(psi)) / 2, 0.02) << x << "," << y << " d=" << d;
      EXPECT_NEAR(f.cone_cos[i], psi / kPi, 0.025) << x << "," << y << " d=" << d;
    }
  EXPECT_GT(checked, 100);
}

TEST(ReducedSearch, FramesSmallerThanTheScaleGiveFiniteResults) {
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {2, 3}, {5, 3}, {9, 7}})
    for (int n = 1; n <= 8; ++n) {
      const Camera cam = test::look_at(w, h, 60, {0.4, 2.0, 1.5}, {0, 0, 0.2});
      GBuffer g = test::ray_cast(cam, test::v_groove(75 * kPi / 180));
      g.diffcol.assign(g.pixels(), Vec3{0.5f, 0.5f, 0.5f});
      g.diffdir.assign(g.pixels(), Vec3{1, 1, 1});
      Params p;
      p.search_scale = n;
      p.outputs = {"ao", "bentcone", "irradiance"};
      const AoFrame f = compute_ao_frame(g, cam, p);
      ASSERT_EQ(f.ao.size(), g.pixels());
      for (size_t i = 0; i < g.pixels(); ++i) {
        EXPECT_TRUE(f.ao[i] >= 0.f && f.ao[i] <= 1.f) << w << "x" << h << " n=" << n;
        EXPECT_TRUE(std::isfinite(f.irradiance[i].x)) << w << "x" << h << " n=" << n;
        EXPECT_TRUE(std::isfinite(f.bent[i].x) && std::isfinite(f.cone_cos[i]));
      }
    }
}

TEST(ReducedSearch, IdenticalBytesForAnyThreadCount) {
  Camera cam;
  GBuffer g = test::busy_scene(cam);
  g.diffcol.assign(g.pixels(), Vec3{0.8f, 0.5f, 0.2f});
  g.diffdir.assign(g.pixels(), Vec3{1, 1, 1});
  Params p;
  p.search_scale = 2;
  p.outputs = {"ao", "bentcone", "irradiance"};
  AoFrame one, many;
  tbb::task_arena(1).execute([&] { one = compute_ao_frame(g, cam, p); });
  tbb::task_arena(4).execute([&] { many = compute_ao_frame(g, cam, p); });
  EXPECT_EQ(0, std::memcmp(one.ao.data(), many.ao.data(), one.ao.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(one.bent.data(), many.bent.data(), one.bent.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(one.irradiance.data(), many.irradiance.data(),
                           one.irradiance.size() * sizeof(Vec3)));
}

}  // namespace
}  // namespace hbil
