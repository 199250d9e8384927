// pushpull_test.cpp: depth-aware push/pull hole filling on synthetic images.
#include "hbil/pushpull.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "hbil/error.h"

namespace hbil {
namespace {

struct Image {
  int w, h, c;
  std::vector<float> value, depth;
  std::vector<uint8_t> valid;
  Image(int w_, int h_, int c_)
      : w(w_),
        h(h_),
        c(c_),
        value(size_t(w_) * h_ * c_),
        depth(size_t(w_) * h_, 2.f),
        valid(size_t(w_) * h_, 1) {}
  size_t at(int x, int y) const { return size_t(y) * w + x; }
  // Marks the rectangle [x0, x1] x [y0, y1] (clipped) as a hole with garbage values.
  void hole(int x0, int y0, int x1, int y1) {
    for (int y = std::max(0, y0); y <= std::min(h - 1, y1); ++y)
      for (int x = std::max(0, x0); x <= std::min(w - 1, x1); ++x) {
        valid[at(x, y)] = 0;
        for (int k = 0; k < c; ++k) value[at(x, y) * c + k] = -999.f;
      }
  }
  std::vector<float> fill(float tol, std::vector<uint8_t>* filled) const {
    return push_pull(w, h, c, value, valid, depth, tol, filled);
  }
};

void expect_valid_unchanged(const Image& im, const std::vector<float>& out) {
  for (size_t i = 0; i < im.valid.size(); ++i)
    if (im.valid[i])
      ASSERT_EQ(0, std::memcmp(&out[i * im.c], &im.value[i * im.c], im.c * sizeof(float))) << i;
}

TEST(PushPull, HoleInConstantRegionGetsTheConstant) {
  // Powers of two, odd sizes and single rows or columns.
  for (const auto& [w, h] :
       std::vector<std::pair<int, int>>{{64, 64}, {61, 47}, {37, 1}, {1, 29}, {13, 200}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    Image im(w, h, 2);
    for (size_t i = 0; i < im.valid.size(); ++i) {
      im.value[2 * i] = 0.3f;
      im.value[2 * i + 1] = 7.25f;
    }
    const int cx = w / 2, cy = h / 2;
    im.hole(cx - 4, cy - 4, cx + 4, cy + 4);  // 9x9 where the image allows
    std::vector<uint8_t> filled;
    const std::vector<float> out = im.fill(0.05f, &filled);
    expect_valid_unchanged(im, out);
    int holes = 0;
    for (size_t i = 0; i < im.valid.size(); ++i) {
      EXPECT_EQ(filled[i], im.valid[i] ? 0 : 1);
      if (im.valid[i]) continue;
      ++holes;
      EXPECT_NEAR(out[2 * i], 0.3f, 1e-6);
      EXPECT_NEAR(out[2 * i + 1], 7.25f, 1e-6);
    }
    EXPECT_EQ(holes, std::min(w, 9) * std::min(h, 9));
  }
}

TEST(PushPull, HoleInGradientFollowsTheGradient) {
  // value = 1 + 0.02 x + 0.01 y (and a second, steeper channel) on a receding surface whose
  // depth grows 1 % per row, so the whole image is one depth layer.
  const int w = 96, h = 80;
  Image im(w, h, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = im.at(x, y);
      im.value[2 * i] = 1 + 0.02f * x + 0.01f * y;
      im.value[2 * i + 1] = -0.05f * x + 0.03f * y;
      im.depth[i] = 2 * std::pow(1.01f, float(y));
    }
  im.hole(40, 30, 48, 38);  // 9x9
  im.hole(5, 60, 7, 77);    // 3x18 strip
  std::vector<uint8_t> filled;
  const std::vector<float> out = im.fill(0.05f, &filled);
  expect_valid_unchanged(im, out);
  double worst0 = 0, worst1 = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = im.at(x, y);
      if (im.valid[i]) continue;
      ASSERT_TRUE(filled[i]);
      worst0 = std::max(worst0, std::fabs(out[2 * i] - (1 + 0.02 * x + 0.01 * y)));
      worst1 = std::max(worst1, std::fabs(out[2 * i + 1] - (-0.05 * x + 0.03 * y)));
    }
  // Within 0.6 pixel's worth of gradient (|grad| = 0.0224 / 0.0583 per pixel); measured worst
  // errors 0.0074 / 0.0274 (0.33 / 0.47 pixel).
  EXPECT_LT(worst0, 0.6 * 0.0224);
  EXPECT_LT(worst1, 0.6 * 0.0583);
}

TEST(PushPull, DepthEdgeKeepsLayersApart) {
  // Left half foreground (depth 1, value A), right half background (depth 5, value B).
  const int w = 64, h = 48;
  const float A[2] = {1.f, 0.f}, B[2] = {0.f, 1.f};
  auto make = [&] {
    Image im(w, h, 2);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = im.at(x, y);
        const bool fg = x < 32;
        im.depth[i] = fg ? 1.f : 5.f;
        im.value[2 * i] = fg ? A[0] : B[0];
        im.value[2 * i + 1] = fg ? A[1] : B[1];
      }
    im.hole(32, 4, 42, 14);   // background, touching the edge
    im.hole(21, 20, 31, 30);  // foreground, touching the edge
    im.hole(24, 34, 40, 46);  // straddling the edge
    return im;
  };
  const Image im = make();
  std::vector<uint8_t> filled;
  const std::vector<float> out = im.fill(0.05f, &filled);
  expect_valid_unchanged(im, out);
  int holes = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = im.at(x, y);
      if (im.valid[i]) continue;
      ++holes;
      ASSERT_TRUE(filled[i]) << x << "," << y;
      const float* want = x < 32 ? A : B;
      EXPECT_NEAR(out[2 * i], want[0], 1e-6) << x << "," << y;
      EXPECT_NEAR(out[2 * i + 1], want[1], 1e-6) << x << "," << y;
    }
  EXPECT_EQ(holes, 121 + 121 + 17 * 13);

  // The same image with a tolerance that merges both layers does mix them: the test above
  // would fail without depth awareness.
  const std::vector<float> mixed = im.fill(10.f, nullptr);
  double most = 0;
  for (int y = 4; y <= 14; ++y)
    for (int x = 32; x <= 42; ++x) most = std::max(most, double(mixed[2 * im.at(x, y)]));
  EXPECT_GT(most, 0.1);
}

TEST(PushPull, NothingToFillFrom) {
  const int w = 40, h = 30;
  // No valid pixel at all.
  Image none(w, h, 3);
  none.hole(0, 0, w - 1, h - 1);
  std::vector<uint8_t> filled;
  std::vector<float> out = none.fill(0.05f, &filled);
  EXPECT_EQ(out, std::vector<float>(size_t(w) * h * 3, 0.f));
  EXPECT_EQ(filled, std::vector<uint8_t>(size_t(w) * h, 0));

  // Background pixels (depth >= 1e30, or not finite) are never filled; valid background
  // pixels are copied but feed nothing; a hole whose depth layer has no valid pixel stays empty.
  Image im(w, h, 1);
  for (size_t i = 0; i < im.valid.size(); ++i) im.value[i] = 3.f;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < 10; ++x) {
      im.depth[im.at(x, y)] = x < 5 ? 1e30f : INFINITY;  // background columns
      im.valid[im.at(x, y)] = y % 2;                     // half of them "valid" with value 9
      im.value[im.at(x, y)] = 9.f;
    }
  im.hole(20, 10, 26, 16);  // ordinary hole, depth 2
  for (int y = 12; y <= 14; ++y)
    for (int x = 22; x <= 24; ++x) im.depth[im.at(x, y)] = 40.f;  // its own layer inside
  out = im.fill(0.05f, &filled);
  expect_valid_unchanged(im, out);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = im.at(x, y);
      if (x < 10) {
        EXPECT_FALSE(filled[i]);
        EXPECT_EQ(out[i], y % 2 ? 9.f : 0.f);
      } else if (!im.valid[i]) {
        const bool own_layer = im.depth[i] == 40.f;
        EXPECT_EQ(filled[i], own_layer ? 0 : 1) << x << "," << y;
        EXPECT_NEAR(out[i], own_layer ? 0.f : 3.f, 1e-6) << x << "," << y;
      }
    }

  // Only background is valid: the depth-2 holes get nothing.
  Image bg(w, h, 1);
  for (size_t i = 0; i < bg.valid.size(); ++i) {
    const bool b = i % 3 == 0;
    bg.depth[i] = b ? 1e31f : 2.f;
    bg.valid[i] = b;
    bg.value[i] = 5.f;
  }
  out = bg.fill(0.05f, &filled);
  for (size_t i = 0; i < bg.valid.size(); ++i) {
    EXPECT_FALSE(filled[i]);
    EXPECT_EQ(out[i], bg.valid[i] ? 5.f : 0.f);
  }

  EXPECT_THROW(push_pull(4, 4, 1, std::vector<float>(15), std::vector<uint8_t>(16),
                         std::vector<float>(16), 0.05f),
               Error);
  EXPECT_TRUE(push_pull(0, 0, 2, {}, {}, {}, 0.05f).empty());
}

TEST(PushPull, IndependentOfThreadCount) {
  // Several depth layers, random values and random holes of all sizes.
  const int w = 203, h = 157, c = 3;
  Image im(w, h, c);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = im.at(x, y);
      const int layer = (x / 23 + y / 31) % 4;
      im.depth[i] = layer == 3 ? 3e38f : (1.f + layer * 2.f) * (1 + 0.002f * y);
      for (int k = 0; k < c; ++k) im.value[i * c + k] = u(rng);
      im.valid[i] = u(rng) < 0.6f;
    }
  for (int k = 0; k < 12; ++k) {
    const int x = int(u(rng) * w), y = int(u(rng) * h), s = 1 + int(u(rng) * 30);
    im.hole(x, y, x + s, y + s);
  }
  std::vector<uint8_t> f1, fn;
  std::vector<float> o1, on;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    o1 = im.fill(0.05f, &f1);
  }
  {
    tbb::global_control many(tbb::global_control::max_allowed_parallelism, 8);
    tbb::task_arena(8).execute([&] { on = im.fill(0.05f, &fn); });
  }
  ASSERT_EQ(o1.size(), on.size());
  EXPECT_EQ(0, std::memcmp(o1.data(), on.data(), o1.size() * sizeof(float)));
  EXPECT_EQ(f1, fn);
  int n = 0;
  for (uint8_t f : f1) n += f;
  EXPECT_GT(n, 1000);  // a real workload: many holes were filled
}

}  // namespace
}  // namespace hbil
