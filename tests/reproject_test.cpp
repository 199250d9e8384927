// reproject_test.cpp: scatter and gather reprojection on ray-cast half-plane scenes.
#include "hbil/reproject.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "analytic_scenes.h"
#include "hbil/error.h"

namespace hbil {
namespace {

constexpr int kW = 160, kH = 120;

ViewGBuffer render(const Camera& cam, const std::vector<test::HalfPlane>& scene) {
  return make_view_gbuffer(test::ray_cast(cam, scene), cam, Params{});
}

Vec3d world_of(const ViewGBuffer& g, const Camera& cam, size_t i) {
  return cam.view_to_world(Vec3d(g.position[i]));
}

// 4 channels per pixel: the world position of the pixel's surface point and its own index.
std::vector<float> world_and_index(const ViewGBuffer& g, const Camera& cam) {
  std::vector<float> v(g.pixels() * 4, 0.f);
  for (size_t i = 0; i < g.pixels(); ++i) {
    if (!g.is_background(i)) {
      const Vec3d p = world_of(g, cam, i);
      v[4 * i] = float(p.x);
      v[4 * i + 1] = float(p.y);
      v[4 * i + 2] = float(p.z);
    }
    v[4 * i + 3] = float(i);
  }
  return v;
}

// Exact motion vectors: the current pixel's surface point projected with the previous camera.
std::vector<float> exact_motion(const ViewGBuffer& cur, const Camera& cur_cam,
                                const Camera& prev_cam) {
  std::vector<float> m(cur.pixels() * 2, 0.f);
  for (int y = 0; y < cur.height; ++y)
    for (int x = 0; x < cur.width; ++x) {
      const size_t i = size_t(y) * cur.width + x;
      if (cur.is_background(i)) continue;
      double u, v;
      prev_cam.project(prev_cam.world_to_view(world_of(cur, cur_cam, i)), u, v);
      m[2 * i] = float(u - (x + 0.5));
      m[2 * i + 1] = float(v - (y + 0.5));
    }
  return m;
}

// Whether the current pixel's surface point was visible in the previous frame: it projects
// inside the previous image onto a pixel that shows the same depth (within 5 %).
bool visible_before(const ViewGBuffer& prev, const Camera& prev_cam, const ViewGBuffer& cur,
                    const Camera& cur_cam, size_t i) {
  if (cur.is_background(i)) return false;
  const Vec3d pv = prev_cam.world_to_view(world_of(cur, cur_cam, i));
  double u, v;
  prev_cam.project(pv, u, v);
  if (!(u >= 0 && u < prev.width && v >= 0 && v < prev.height)) return false;
  const size_t s = size_t(std::floor(v)) * prev.width + size_t(std::floor(u));
  return !prev.is_background(s) && std::fabs(prev.position[s].z - pv.z) <= 0.05 * pv.z;
}

// How far the surface point of pixel i can be from points seen inside the same pixel: the
// largest distance from it to where the rays through the pixel's corners meet its tangent
// plane (world units; infinite when a corner ray misses the plane).
double footprint(const ViewGBuffer& g, const Camera& cam, size_t i) {
  const Vec3d P(g.position[i]), n(g.normal[i]);
  const double x = double(i % g.width), y = double(i / g.width);
  double r = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec3d d{(x + (k & 1) - cam.cx) / cam.fx, (y + (k >> 1) - cam.cy) / cam.fy, 1};
    const double t = dot(n, P) / dot(n, d);
    if (!(t > 0) || !std::isfinite(t)) return INFINITY;
    r = std::max(r, length(d * t - P));
  }
  return r;
}

// A floor, a back wall 3 units high (sky above it) and a vertical pillar in front.
std::vector<test::HalfPlane> room() {
  return {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},
          {{0, 0, 0}, {0, 0, 1}, {0, -1, 0}},
          {{0, 6, 0}, {0, 1, 0}, {0, 0, 1}, 3.0},
          {{-0.5, 1, 0}, {0, 1, 0}, {1, 0, 0}, 1.0}};
}

// The room scaled by s about the point c (depth order and view rays through c unchanged).
std::vector<test::HalfPlane> scaled(std::vector<test::HalfPlane> planes, Vec3d c, double s) {
  for (test::HalfPlane& p : planes) {
    p.origin = c + (p.origin - c) * s;
    p.length *= s;
  }
  return planes;
}

const Vec3d kEye{0.3, -6, 1.5};

// Current camera: the previous one turned `yaw_deg` about the world z axis through the eye.
Camera yawed(double yaw_deg) {
  const double a = yaw_deg * M_PI / 180, dx = 0.3, dy = 6;  // target - eye = (-0.3, 6, -0.3)
  const Vec3d dir{-dx * std::cos(a) - dy * std::sin(a), -dx * std::sin(a) + dy * std::cos(a), -0.3};
  return test::look_at(kW, kH, 60, kEye, kEye + dir);
}

TEST(ReprojectScatter, PureRotationFollowsTheHomography) {
  const Camera prev_cam = yawed(0), cur_cam = yawed(4);
  const ViewGBuffer prev = render(prev_cam, room()), cur = render(cur_cam, room());
  const std::vector<float> pv = world_and_index(prev, prev_cam);
  const Reprojected r = reproject_scatter(prev, prev_cam, pv, 4, cur, cur_cam);
  ASSERT_EQ(r.width, kW);
  ASSERT_EQ(r.height, kH);
  ASSERT_EQ(r.channels, 4);

  // Homography of a pure rotation: raster_cur ~ K R_cur R_prev^T K^-1 raster_prev.
  const Mat3d Rrel = cur_cam.R * prev_cam.R.transposed();
  auto map = [&](double u, double v, double& uc, double& vc) {
    const Vec3d d =
        Rrel * Vec3d{(u - prev_cam.cx) / prev_cam.fx, (v - prev_cam.cy) / prev_cam.fy, 1};
    uc = cur_cam.fx * d.x / d.z + cur_cam.cx;
    vc = cur_cam.fy * d.y / d.z + cur_cam.cy;
  };

  int visible = 0, valid_visible = 0, valid = 0, off_homography = 0, off_footprint = 0;
  double worst_rel = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      const bool vis = visible_before(prev, prev_cam, cur, cur_cam, i);
      visible += vis;
      if (!r.valid[i]) continue;
      ++valid;
      valid_visible += vis;
      // The source pixel's centre maps into this pixel, whatever its depth.
      const int s = int(r.value[4 * i + 3]);
      double uc, vc;
      map(s % kW + 0.5, s / kW + 0.5, uc, vc);
      if (!(uc > x - 1e-3 && uc < x + 1 + 1e-3 && vc > y - 1e-3 && vc < y + 1 + 1e-3))
        ++off_homography;
      // The reprojected world position is the current pixel's own up to the pixel footprint
      // (nearest-neighbour splat).
      const Vec3d pw = world_of(cur, cur_cam, i);
      const Vec3d got{r.value[4 * i], r.value[4 * i + 1], r.value[4 * i + 2]};
      const double z = cur.position[i].z;
      off_footprint += length(got - pw) > footprint(cur, cur_cam, i) + 1e-5 * z;
      worst_rel = std::max(worst_rel, length(got - pw) / z);
    }
  // Measured: 13 098 pixels visible in both frames, 12 769 valid, 12 768 of them visible
  // (97.5 % of the visible; the rest are splat gaps), none off the homography or outside the
  // footprint, worst |error| 0.032 z (grazing floor, where the footprint is that large).
  EXPECT_GT(visible, kW * kH / 2);
  EXPECT_LE(valid - valid_visible, 2) << "valid pixels must have been visible before";
  EXPECT_GT(double(valid_visible) / visible, 0.97);
  EXPECT_EQ(off_homography, 0);
  EXPECT_EQ(off_footprint, 0) << "worst " << worst_rel;
  EXPECT_LT(worst_rel, 0.05);

  // A few pixels explicitly: pillar, wall, floor near and far map as the homography says.
  for (const auto& [x, y] :
       std::vector<std::pair<int, int>>{{80, 60}, {40, 45}, {20, 110}, {130, 70}}) {
    const size_t s = size_t(y) * kW + x;
    ASSERT_FALSE(prev.is_background(s));
    double uc, vc;
    map(x + 0.5, y + 0.5, uc, vc);
    const size_t t = size_t(std::floor(vc)) * kW + size_t(std::floor(uc));
    ASSERT_TRUE(r.valid[t]) << x << "," << y;
    // The pixel that received it holds the same surface point within a pixel footprint.
    const Vec3d want = world_of(prev, prev_cam, s);
    const Vec3d got{r.value[4 * t], r.value[4 * t + 1], r.value[4 * t + 2]};
    EXPECT_LT(length(got - want), 2.0 * cur.position[t].z / cur_cam.fx) << x << "," << y;
  }

  // Independent of depth: the same rotation of a room twice as large (about the eye) moves
  // every pixel to the same place, so the same sources win.
  const ViewGBuffer prev2 = render(prev_cam, scaled(room(), kEye, 2.0));
  const ViewGBuffer cur2 = render(cur_cam, scaled(room(), kEye, 2.0));
  const Reprojected r2 =
      reproject_scatter(prev2, prev_cam, world_and_index(prev2, prev_cam), 4, cur2, cur_cam);
  int differ = 0;
  for (size_t i = 0; i < cur.pixels(); ++i)
    differ += r.valid[i] != r2.valid[i] || r.value[4 * i + 3] != r2.value[4 * i + 3];
  EXPECT_LE(differ, 2);  // measured: 0
}

TEST(ReprojectScatter, DisoccludedPixelsAreNotValid) {
  // A wall at y = 6 behind a pillar at y = 1 (x in [-0.5, 0.5]); the camera moves 1.5 right.
  const std::vector<test::HalfPlane> scene = {{{0, 6, 0}, {0, 1, 0}, {0, 0, 1}},
                                              {{0, 6, 0}, {0, 1, 0}, {0, 0, -1}},
                                              {{-0.5, 1, 0}, {0, 1, 0}, {1, 0, 0}, 1.0}};
  const Camera prev_cam = test::look_at(kW, kH, 60, {0, -6, 0}, {0, 0, 0});
  const Camera cur_cam = test::look_at(kW, kH, 60, {1.5, -6, 0}, {1.5, 0, 0});
  const ViewGBuffer prev = render(prev_cam, scene), cur = render(cur_cam, scene);
  const Reprojected r =
      reproject_scatter(prev, prev_cam, world_and_index(prev, prev_cam), 4, cur, cur_cam);
  const Reprojected g = reproject_gather(prev, prev_cam, world_and_index(prev, prev_cam), 4, cur,
                                         cur_cam, exact_motion(cur, cur_cam, prev_cam));
  int hidden = 0, hidden_valid_scatter = 0, hidden_valid_gather = 0, seen = 0, seen_valid = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      ASSERT_FALSE(cur.is_background(i));
      const Vec3d pv = prev_cam.world_to_view(world_of(cur, cur_cam, i));
      double u, v;
      prev_cam.project(pv, u, v);
      if (!(u >= 3 && u < kW - 3)) continue;
      // Hidden before: the previous pixels within 2 columns of its projection all show
      // something nearer (the pillar).
      bool all_nearer = true, all_same = true;
      for (int dx = -2; dx <= 2; ++dx) {
        const size_t s = size_t(std::floor(v)) * kW + size_t(std::floor(u) + dx);
        all_nearer = all_nearer && prev.position[s].z < 0.9 * pv.z;
        all_same = all_same && std::fabs(prev.position[s].z - pv.z) < 0.01 * pv.z;
      }
      if (all_nearer) {
        ++hidden;
        hidden_valid_scatter += r.valid[i];
        hidden_valid_gather += g.valid[i];
      }
      if (all_same) {
        ++seen;
        seen_valid += r.valid[i];
      }
    }
  // Measured: 1 320 hidden pixels (11 columns), none valid; 14 520 clearly visible, all valid.
  EXPECT_GT(hidden, 2 * kH);
  EXPECT_EQ(hidden_valid_scatter, 0);
  EXPECT_EQ(hidden_valid_gather, 0);
  EXPECT_GT(seen, kW * kH / 2);
  EXPECT_EQ(seen_valid, seen);
}

TEST(ReprojectScatter, DepthAndNormalTolerances) {
  // Same camera, fronto-parallel planes: every previous pixel lands on its own pixel.
  const Camera cam = test::look_at(32, 24, 60, {0, 0, 0}, {0, 1, 0});
  auto plane = [&](double z, Vec3 n) {
    ViewGBuffer g;
    g.width = 32;
    g.height = 24;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 32; ++x) {
        g.position.push_back(Vec3(cam.unproject(x + 0.5, y + 0.5, z)));
        g.normal.push_back(n);
      }
    return g;
  };
  const Vec3 facing{0, 0, -1};
  const ViewGBuffer prev = plane(5, facing);
  std::vector<float> value(prev.pixels());
  for (size_t i = 0; i < value.size(); ++i) value[i] = 0.5f + float(i);
  auto count_valid = [&](const ViewGBuffer& cur) {
    const Reprojected r = reproject_scatter(prev, cam, value, 1, cur, cam);
    int n = 0;
    for (size_t i = 0; i < r.valid.size(); ++i) {
      n += r.valid[i];
      if (r.valid[i])
        EXPECT_EQ(r.value[i], value[i]);
      else
        EXPECT_EQ(r.value[i], 0.f);
    }
    return n;
  };
  const int all = 32 * 24;
  EXPECT_EQ(count_valid(plane(5, facing)), all);
  EXPECT_EQ(count_valid(plane(5.2, facing)), all);  // 3.8 % deeper: within 5 %
  EXPECT_EQ(count_valid(plane(4.7, facing)), 0);    // 6.4 % nearer
  EXPECT_EQ(count_valid(plane(5.5, facing)), 0);
  const double c30 = std::cos(M_PI / 6), c45 = std::cos(M_PI / 4);
  EXPECT_EQ(count_valid(plane(5, Vec3(Vec3d{0, 0.5, -c30}))), all);  // 30 degrees: cos 0.87
  EXPECT_EQ(count_valid(plane(5, Vec3(Vec3d{0, c45, -c45}))), 0);    // 45 degrees: cos 0.71
  // Tighter tolerances reject what the defaults accept.
  EXPECT_EQ(reproject_scatter(prev, cam, value, 1, plane(5.2, facing), cam, {0.03f, 0.8f}).valid,
            std::vector<uint8_t>(all, 0));
}

TEST(ReprojectGather, MatchesScatterWithExactMotion) {
  for (const bool rotate : {true, false}) {
    const Camera prev_cam = yawed(0);
    const Camera cur_cam = rotate ? yawed(-3)
                                  : test::look_at(kW, kH, 60, kEye + Vec3d{0.4, 0.3, 0.1},
                                                  kEye + Vec3d{0.1, 6.3, -0.2});
    const ViewGBuffer prev = render(prev_cam, room()), cur = render(cur_cam, room());
    const std::vector<float> pv = world_and_index(prev, prev_cam);
    const Reprojected s = reproject_scatter(prev, prev_cam, pv, 4, cur, cur_cam);
    const Reprojected g =
        reproject_gather(prev, prev_cam, pv, 4, cur, cur_cam, exact_motion(cur, cur_cam, prev_cam));
    int both = 0, scatter_only = 0, gather_only = 0, apart = 0, gather_off = 0, gather_far = 0;
    double worst_vs_scatter = 0, worst_gather = 0;
    for (size_t i = 0; i < cur.pixels(); ++i) {
      if (cur.is_background(i)) continue;
      scatter_only += s.valid[i] && !g.valid[i];
      gather_only += !s.valid[i] && g.valid[i];
      if (!(s.valid[i] && g.valid[i])) continue;
      ++both;
      const double z = cur.position[i].z;
      const Vec3d vs{s.value[4 * i], s.value[4 * i + 1], s.value[4 * i + 2]};
      const Vec3d vg{g.value[4 * i], g.value[4 * i + 1], g.value[4 * i + 2]};
      // Scatter is the nearest splat inside the pixel, gather interpolates at the exact point.
      const double fp = footprint(cur, cur_cam, i);
      apart += length(vs - vg) > fp + 1e-5 * z;
      worst_vs_scatter = std::max(worst_vs_scatter, length(vs - vg) / fp);
      const double e = length(vg - world_of(cur, cur_cam, i)) / fp;
      worst_gather = std::max(worst_gather, e);
      gather_off += e > 0.05;
      gather_far += e > 1;
    }
    // Measured (rotation / translation): 13 043 / 11 751 pixels valid in both, 0 / 0 valid in
    // scatter only (326 / 1 848 in gather only: splat gaps); scatter within the footprint of
    // gather everywhere (worst 0.98 / 1.00 footprints); gather off the truth by more than 5 %
    // of a footprint on 365 / 405 pixels (perspective on the grazing floor, silhouettes where
    // neighbours drop out), worst 0.90 / 0.82 footprints.
    SCOPED_TRACE(rotate ? "rotation" : "translation");
    EXPECT_GT(both, kW * kH / 2);
    EXPECT_LE(scatter_only, both / 1000);
    EXPECT_EQ(apart, 0) << "worst " << worst_vs_scatter;
    EXPECT_EQ(gather_far, 0) << "worst " << worst_gather;
    EXPECT_LE(gather_off, both / 20);
  }
}

TEST(ReprojectGather, BilinearWeightsAndRejection) {
  // Same camera and plane; motion (0.25, 0.5) interpolates the value x + 100 y bilinearly.
  const Camera cam = test::look_at(16, 12, 20, {0, 0, 0}, {0, 1, 0});
  ViewGBuffer g;
  g.width = 16;
  g.height = 12;
  std::vector<float> value;
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x) {
      g.position.push_back(Vec3(cam.unproject(x + 0.5, y + 0.5, 40)));
      g.normal.push_back({0, 0, -1});
      value.push_back(float(x + 100 * y));
    }
  std::vector<float> motion(g.pixels() * 2);
  for (size_t i = 0; i < g.pixels(); ++i) motion[2 * i] = 0.25f, motion[2 * i + 1] = 0.5f;
  const Reprojected r = reproject_gather(g, cam, value, 1, g, cam, motion);
  for (int y = 0; y < 11; ++y)
    for (int x = 0; x < 15; ++x) {
      const size_t i = size_t(y) * 16 + x;
      ASSERT_TRUE(r.valid[i]);
      EXPECT_NEAR(r.value[i], x + 0.25 + 100 * (y + 0.5), 1e-4);
    }
  // Last column: the right neighbours are off the image, the left ones keep all the weight.
  EXPECT_NEAR(r.value[5 * 16 + 15], 15 + 100 * 5.5, 1e-4);
  // A previous pixel on another surface (background here) drops out, the rest renormalise.
  ViewGBuffer prev = g;
  prev.position[3 * 16 + 5].z = ViewGBuffer::kBackground;
  prev.normal[3 * 16 + 5] = {};
  const Reprojected r2 = reproject_gather(prev, cam, value, 1, g, cam, motion);
  // Pixel (4, 3) samples (4..5, 3..4) with weights 3/8, 1/8, 3/8, 1/8 before dropping (5, 3).
  const double want = (0.375 * 304 + 0.375 * 404 + 0.125 * 405) / 0.875;
  EXPECT_NEAR(r2.value[3 * 16 + 4], want, 1e-4);
  // Motion pointing off the image or not finite: invalid.
  motion[2 * 7] = -20;
  motion[2 * 8] = std::nanf("");
  const Reprojected r3 = reproject_gather(g, cam, value, 1, g, cam, motion);
  EXPECT_FALSE(r3.valid[7]);
  EXPECT_FALSE(r3.valid[8]);
  EXPECT_EQ(r3.value[7], 0.f);
}

TEST(ReprojectScatter, BackgroundNeverValidAndThreadCountIndependent) {
  const Camera prev_cam = yawed(0);
  const Camera cur_cam =
      test::look_at(kW, kH, 60, kEye + Vec3d{-0.5, 0.8, 0.2}, kEye + Vec3d{-0.2, 6.8, 0.3});
  const ViewGBuffer prev = render(prev_cam, room()), cur = render(cur_cam, room());
  std::vector<float> pv = world_and_index(prev, prev_cam);
  // Background pixels carry a value too: it must never be moved.
  int prev_bg = 0, cur_bg = 0;
  for (size_t i = 0; i < prev.pixels(); ++i)
    if (prev.is_background(i)) pv[4 * i] = 1e6f, ++prev_bg;
  const std::vector<float> motion = exact_motion(cur, cur_cam, prev_cam);

  Reprojected s1, g1, sn, gn;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    s1 = reproject_scatter(prev, prev_cam, pv, 4, cur, cur_cam);
    g1 = reproject_gather(prev, prev_cam, pv, 4, cur, cur_cam, motion);
  }
  {
    tbb::global_control many(tbb::global_control::max_allowed_parallelism, 8);
    tbb::task_arena(8).execute([&] {
      sn = reproject_scatter(prev, prev_cam, pv, 4, cur, cur_cam);
      gn = reproject_gather(prev, prev_cam, pv, 4, cur, cur_cam, motion);
    });
  }
  for (size_t i = 0; i < cur.pixels(); ++i) {
    if (!cur.is_background(i)) continue;
    ++cur_bg;
    EXPECT_FALSE(s1.valid[i]);
    EXPECT_FALSE(g1.valid[i]);
    for (int c = 0; c < 4; ++c) EXPECT_EQ(s1.value[4 * i + c], 0.f);
  }
  for (size_t i = 0; i < cur.pixels(); ++i) {
    EXPECT_LT(s1.value[4 * i], 1e5f);
    EXPECT_LT(g1.value[4 * i], 1e5f);
  }
  EXPECT_GT(prev_bg, 500);  // the sky above the wall
  EXPECT_GT(cur_bg, 500);
  ASSERT_EQ(s1.value.size(), sn.value.size());
  EXPECT_EQ(0, std::memcmp(s1.value.data(), sn.value.data(), s1.value.size() * sizeof(float)));
  EXPECT_EQ(s1.valid, sn.valid);
  ASSERT_EQ(g1.value.size(), gn.value.size());
  EXPECT_EQ(0, std::memcmp(g1.value.data(), gn.value.data(), g1.value.size() * sizeof(float)));
  EXPECT_EQ(g1.valid, gn.valid);

  // A previous frame of nothing but background gives nothing.
  ViewGBuffer empty = prev;
  for (Vec3& p : empty.position) p.z = ViewGBuffer::kBackground;
  for (Vec3& n : empty.normal) n = {};
  const Reprojected e = reproject_scatter(empty, prev_cam, pv, 4, cur, cur_cam);
  EXPECT_EQ(e.valid, std::vector<uint8_t>(cur.pixels(), 0));
  EXPECT_EQ(e.value, std::vector<float>(cur.pixels() * 4, 0.f));
}

TEST(ReprojectScatter, RejectsMismatchedSizes) {
  const Camera cam = test::look_at(8, 6, 60, {0, 0, 0}, {0, 1, 0});
  const ViewGBuffer g = render(cam, {{{0, 5, 0}, {0, 1, 0}, {0, 0, 1}}});
  EXPECT_THROW(reproject_scatter(g, cam, std::vector<float>(10), 2, g, cam), Error);
  EXPECT_THROW(reproject_gather(g, cam, std::vector<float>(48), 1, g, cam, std::vector<float>(5)),
               Error);
}

}  // namespace
}  // namespace hbil
