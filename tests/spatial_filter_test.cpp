// spatial_filter_test.cpp: the re-interleave filter (spatial_filter.h): on one surface it is
// the plain mean of the 4x4 window, it never mixes two surfaces, background pixels keep
// their values, and the SIMD runs give the scalar loop's results to the bit, with every
// instruction set the machine has.
#include "hbil/spatial_filter.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <bit>
#include <cstdint>
#include <random>

namespace hbil {
namespace {

// Two fronto-parallel planes, x < split at depth 2 and the rest at depth 5 (normal towards
// the camera), and the search's values: ao = 0.1 x + 0.01 y, the others from it.
struct Scene {
  ViewGBuffer v;
  HorizonImage h;
};
Scene two_planes(int w, int ht, int split, bool irradiance) {
  Scene s;
  s.v.width = s.h.width = w;
  s.v.height = s.h.height = ht;
  for (int y = 0; y < ht; ++y)
    for (int x = 0; x < w; ++x) {
      const float z = x < split ? 2.f : 5.f;
      s.v.position.push_back(Vec3{(x - w / 2.f) * z / 100.f, (y - ht / 2.f) * z / 100.f, z});
      s.v.normal.push_back(Vec3{0, 0, -1});
      const float a = 0.1f * float(x) + 0.01f * float(y);
      s.h.ao.push_back(a);
      s.h.vis.push_back(2 * a);
      s.h.bent.push_back(Vec3{a, -a, 3 * a});
      if (irradiance) s.h.irradiance.push_back(Vec3{4 * a, 5 * a, 6 * a});
    }
  return s;
}

// The mean of ao over the window (offsets −1..2) of (x, y), on the pixels with x < split
// exactly when x is.
double window_mean(const Scene& s, int x, int y, int split) {
  double sum = 0;
  int n = 0;
  for (int yy = y - 1; yy <= y + 2; ++yy)
    for (int xx = x - 1; xx <= x + 2; ++xx) {
      if (xx < 0 || yy < 0 || xx >= s.v.width || yy >= s.v.height) continue;
      if ((xx < split) != (x < split)) continue;
      sum += s.h.ao[size_t(yy) * s.v.width + xx];
      ++n;
    }
  return sum / n;
}

TEST(SpatialFilter, MeanOfTheWindowOnEachSurfaceOnly) {
  for (bool vectorised : {false, true}) {
    const int w = 53, ht = 9, split = 23;
    const Scene s = two_planes(w, ht, split, true);
    const HorizonImage out = spatial_filter(s.v, s.h, 0.05f, vectorised);
    for (int y = 0; y < ht; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const double m = window_mean(s, x, y, split);
        ASSERT_NEAR(out.ao[i], m, 1e-5) << x << "," << y << " vectorised " << vectorised;
        EXPECT_NEAR(out.vis[i], 2 * m, 2e-5);
        EXPECT_NEAR(out.bent[i].z, 3 * m, 3e-5);
        EXPECT_NEAR(out.irradiance[i].y, 5 * m, 5e-5);
      }
  }
}

// Bits of every value of two images.
void expect_same_bits(const HorizonImage& a, const HorizonImage& b) {
  ASSERT_EQ(a.ao.size(), b.ao.size());
  ASSERT_EQ(a.irradiance.size(), b.irradiance.size());
  auto bits = [](float f) { return std::bit_cast<std::uint32_t>(f); };
  size_t diff = 0;
  for (size_t i = 0; i < a.ao.size(); ++i) {
    diff += bits(a.ao[i]) != bits(b.ao[i]) || bits(a.vis[i]) != bits(b.vis[i]);
    for (int c = 0; c < 3; ++c) {
      diff += bits((&a.bent[i].x)[c]) != bits((&b.bent[i].x)[c]);
      if (!a.irradiance.empty())
        diff += bits((&a.irradiance[i].x)[c]) != bits((&b.irradiance[i].x)[c]);
    }
  }
  EXPECT_EQ(diff, 0u);
}

TEST(SpatialFilter, SimdRunsGiveTheScalarResultsToTheBit) {
  // Rough random surfaces (the test passes and fails by neighbour), background pixels, a
  // NaN value, and widths that are no multiple of any vector length.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int w : {3, 4, 5, 19, 40, 97}) {
    for (bool irradiance : {false, true}) {
      const int ht = 7;
      Scene s = two_planes(w, ht, w / 3, irradiance);
      size_t moved = 0;
      for (size_t i = 0; i < s.v.pixels(); ++i) {
        s.v.position[i].z += 0.2f * (u(rng) - 0.5f);
        s.v.normal[i] = normalize_or_zero(Vec3{u(rng) - 0.5f, u(rng) - 0.5f, -1.f});
        if (u(rng) < 0.1f) s.v.position[i].z = ViewGBuffer::kBackground * 2, ++moved;
        s.h.ao[i] = u(rng);
        s.h.bent[i].y = u(rng) - 0.5f;
      }
      if (s.v.pixels() > 20) s.h.vis[20] = std::nanf("");
      const HorizonImage scalar = spatial_filter(s.v, s.h, 0.05f, false);
      // Every instruction set the machine has.
      for (std::int64_t t : hwy::SupportedAndGeneratedTargets()) {
        SCOPED_TRACE(hwy::TargetName(t));
        hwy::SetSupportedTargetsForTest(t);
        expect_same_bits(scalar, spatial_filter(s.v, s.h, 0.05f, true));
      }
      hwy::SetSupportedTargetsForTest(0);
      const HorizonImage simd = spatial_filter(s.v, s.h, 0.05f, true);
      // Background pixels keep the input's values.
      for (size_t i = 0; i < s.v.pixels(); ++i)
        if (s.v.is_background(i)) EXPECT_EQ(simd.ao[i], s.h.ao[i]);
      // The test is not vacuous: the filter changed most geometry pixels.
      size_t changed = 0;
      for (size_t i = 0; i < s.v.pixels(); ++i) changed += simd.ao[i] != s.h.ao[i];
      EXPECT_GT(changed, (s.v.pixels() - moved) / 2) << w;
      if (!irradiance) continue;
      // The irradiance alone (a later in-frame bounce) is filtered to the same bits, by both
      // paths, and stays alone.
      HorizonImage alone;
      alone.width = s.h.width;
      alone.height = s.h.height;
      alone.irradiance = s.h.irradiance;
      ASSERT_TRUE(alone.irradiance_only());
      for (bool vectorised : {false, true}) {
        const HorizonImage a = spatial_filter(s.v, alone, 0.05f, vectorised);
        EXPECT_TRUE(a.ao.empty() && a.vis.empty() && a.bent.empty());
        HorizonImage whole = vectorised ? simd : scalar;
        whole.ao.clear(), whole.vis.clear(), whole.bent.clear();
        expect_same_bits(a, whole);
      }
    }
  }
}

}  // namespace
}  // namespace hbil
