// reproject.cpp: see reproject.h.
#include "hbil/reproject.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "hbil/error.h"

namespace hbil {

namespace {

void check_sizes(const char* fn, const ViewGBuffer& prev, const std::vector<float>& prev_value,
                 int channels, const ViewGBuffer& cur) {
  if (channels < 1)
    throw Error(Exit::failure,
                std::string(fn) + ": channels must be >= 1, got " + std::to_string(channels));
  if (prev.position.size() != prev.pixels() || prev.normal.size() != prev.pixels() ||
      cur.position.size() != cur.pixels() || cur.normal.size() != cur.pixels())
    throw Error(Exit::failure, std::string(fn) + ": G-buffer arrays do not match their size");
  if (prev_value.size() != prev.pixels() * size_t(channels))
    throw Error(Exit::failure, std::string(fn) + ": previous values hold " +
                                   std::to_string(prev_value.size()) + " floats, expected " +
                                   std::to_string(prev.pixels() * size_t(channels)));
}

Reprojected empty_result(const ViewGBuffer& cur, int channels) {
  Reprojected r;
  r.width = cur.width;
  r.height = cur.height;
  r.channels = channels;
  r.value.assign(cur.pixels() * size_t(channels), 0.f);
  r.valid.assign(cur.pixels(), 0);
  return r;
}

}  // namespace

Reprojected reproject_scatter(const ViewGBuffer& prev, const Camera& prev_cam,
                              const std::vector<float>& prev_value, int channels,
                              const ViewGBuffer& cur, const Camera& cur_cam,
                              const ReprojectTolerance& tol) {
  check_sizes("reproject_scatter", prev, prev_value, channels, cur);
  Reprojected r = empty_result(cur, channels);
  const size_t np = prev.pixels(), nc = cur.pixels();
  if (np == 0 || nc == 0) return r;

  // 1. Where each previous pixel lands (parallel, independent per source).
  constexpr int64_t kNone = -1;
  std::vector<int64_t> target(np, kNone);
  std::vector<double> target_z(np, 0.0);
  tbb::parallel_for(0, prev.height, [&](int y) {
    for (int x = 0; x < prev.width; ++x) {
      const size_t s = size_t(y) * prev.width + x;
      if (prev.is_background(s)) continue;
      const Vec3d pw = prev_cam.view_to_world(Vec3d(prev.position[s]));
      const Vec3d pc = cur_cam.world_to_view(pw);
      if (!(pc.z > 0) || !std::isfinite(pc.z)) continue;
      double u, v;
      cur_cam.project(pc, u, v);
      // The pixel, or on a reduced grid (scale f: reduce_view) the texel of its f x f block.
      const double col = std::floor(u / cur.scale), row = std::floor(v / cur.scale);
      if (!(col >= 0 && col < cur.width && row >= 0 && row < cur.height)) continue;
      target[s] = int64_t(row) * cur.width + int64_t(col);
      target_z[s] = pc.z;
    }
  });

  // 2. Z-buffer resolve, serial in source order: the nearest wins, ties the first source.
  std::vector<int64_t> source(nc, kNone);
  std::vector<double> nearest(nc, std::numeric_limits<double>::infinity());
  for (size_t s = 0; s < np; ++s) {
    const int64_t t = target[s];
    if (t == kNone) continue;
    if (target_z[s] < nearest[size_t(t)]) {
      nearest[size_t(t)] = target_z[s];
      source[size_t(t)] = int64_t(s);
    }
  }

  // 3. Accept or reject per current pixel.
  tbb::parallel_for(0, cur.height, [&](int y) {
    for (int x = 0; x < cur.width; ++x) {
      const size_t i = size_t(y) * cur.width + x;
      if (cur.is_background(i) || source[i] == kNone) continue;
      const size_t s = size_t(source[i]);
      const double zc = cur.position[i].z;
      if (!(std::fabs(nearest[i] - zc) <= double(tol.depth) * zc)) continue;
      const Vec3d np_w = prev_cam.view_dir_to_world(Vec3d(prev.normal[s]));
      const Vec3d nc_w = cur_cam.view_dir_to_world(Vec3d(cur.normal[i]));
      if (!(dot(np_w, nc_w) >= double(tol.normal_cos))) continue;
      r.valid[i] = 1;
      for (int c = 0; c < channels; ++c)
        r.value[i * channels + c] = prev_value[s * channels + size_t(c)];
    }
  });
  return r;
}

namespace {

// The history of one current pixel from its previous-frame neighbours, C channels (C = 0:
// `channels` at run time), in floats, as the values are stored.
template <int C>
void gather_row(const ViewGBuffer& prev, const std::vector<float>& prev_value, int channels,
                const ViewGBuffer& cur, const std::vector<float>& motion, const Mat3d& M,
                const Vec3d& m, const ReprojectTolerance& tol, int y, Reprojected& r) {
  const int nc = C > 0 ? C : channels;
  std::vector<float> acc_store(C > 0 ? 0 : size_t(nc));
  float acc_fixed[C > 0 ? C : 1];
  float* acc = C > 0 ? acc_fixed : acc_store.data();
  const float normal_cos = tol.normal_cos;
  for (int x = 0; x < cur.width; ++x) {
    const size_t i = size_t(y) * cur.width + x;
    if (cur.is_background(i)) continue;
    const double du = motion[2 * i], dv = motion[2 * i + 1];
    if (!std::isfinite(du) || !std::isfinite(dv)) continue;
    // Previous raster (x + 0.5 + du, y + 0.5 + dv); pixel centres sit at integer + 0.5.
    const double px = x + du, py = y + dv;
    const double fx0 = std::floor(px), fy0 = std::floor(py);
    // Entirely off the previous image (also guards the int conversion below).
    if (!(fx0 >= -1 && fx0 < prev.width && fy0 >= -1 && fy0 < prev.height)) continue;
    const int x0 = int(fx0), y0 = int(fy0);
    const float ax = float(px - fx0), ay = float(py - fy0);
    const float max_dist = tol.depth * cur.position[i].z;
    const float max_dist2 = max_dist * max_dist;
    // The pixel's point and normal in the previous frame's view space, once, so that the four
    // neighbours are compared where they are stored (distances and angles are the same).
    const Vec3 pp = Vec3(M * Vec3d(cur.position[i]) + m);
    const Vec3 np = Vec3(M * Vec3d(cur.normal[i]));
    for (int c = 0; c < nc; ++c) acc[c] = 0.f;
    float wsum = 0;
    for (int k = 0; k < 4; ++k) {
      const int xx = x0 + (k & 1), yy = y0 + (k >> 1);
      const float w = ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay);
      if (!(w > 0) || xx < 0 || xx >= prev.width || yy < 0 || yy >= prev.height) continue;
      const size_t s = size_t(yy) * prev.width + xx;
      if (prev.is_background(s)) continue;
      const Vec3 d = prev.position[s] - pp;
      if (!(dot(d, d) <= max_dist2)) continue;
      if (!(dot(prev.normal[s], np) >= normal_cos)) continue;
      wsum += w;
      const float* v = prev_value.data() + s * size_t(nc);
      for (int c = 0; c < nc; ++c) acc[c] += w * v[c];
    }
    if (!(wsum > 0)) continue;
    r.valid[i] = 1;
    const float inv = 1 / wsum;
    float* out = r.value.data() + i * size_t(nc);
    for (int c = 0; c < nc; ++c) out[c] = acc[c] * inv;
  }
}

}  // namespace

Reprojected reproject_gather(const ViewGBuffer& prev, const Camera& prev_cam,
                             const std::vector<float>& prev_value, int channels,
                             const ViewGBuffer& cur, const Camera& cur_cam,
                             const std::vector<float>& motion, const ReprojectTolerance& tol) {
  check_sizes("reproject_gather", prev, prev_value, channels, cur);
  if (motion.size() != cur.pixels() * 2)
    throw Error(Exit::failure, "reproject_gather: motion holds " + std::to_string(motion.size()) +
                                   " floats, expected " + std::to_string(cur.pixels() * 2));
  Reprojected r = empty_result(cur, channels);
  if (prev.pixels() == 0 || cur.pixels() == 0) return r;

  // The current view space to the previous one in one rigid motion: v' = M v + m.
  const Mat3d M = prev_cam.R * cur_cam.R.transposed();
  const Vec3d m = prev_cam.t - M * cur_cam.t;
  // The temporal chain's channel counts get a loop of fixed length (9: its history, 6 without
  // irradiance; 21 and 12: with history_window); any other count the general one.
  tbb::parallel_for(0, cur.height, [&](int y) {
    if (channels == 9)
      gather_row<9>(prev, prev_value, channels, cur, motion, M, m, tol, y, r);
    else if (channels == 6)
      gather_row<6>(prev, prev_value, channels, cur, motion, M, m, tol, y, r);
    else if (channels == 21)
      gather_row<21>(prev, prev_value, channels, cur, motion, M, m, tol, y, r);
    else if (channels == 12)
      gather_row<12>(prev, prev_value, channels, cur, motion, M, m, tol, y, r);
    else
      gather_row<0>(prev, prev_value, channels, cur, motion, M, m, tol, y, r);
  });
  return r;
}

}  // namespace hbil
