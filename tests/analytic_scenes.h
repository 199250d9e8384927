// analytic_scenes.h: test scenes made of half-planes, ray cast into a G-buffer with the
// same conventions Blender uses (planar depth, world-space unit normals, 1e10 background).
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "hbil/camera.h"
#include "hbil/gbuffer.h"

namespace hbil::test {

// Pinhole camera at `eye` looking at `target`, world z up, horizontal field of view in degrees.
inline Camera look_at(int w, int h, double fov_deg, Vec3d eye, Vec3d target, Vec3d up = {0, 0, 1}) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fx = c.fy = 0.5 * w / std::tan(0.5 * fov_deg * M_PI / 180.0);
  c.cx = 0.5 * w;
  c.cy = 0.5 * h;
  const Vec3d f = normalize_or_zero(target - eye);
  const Vec3d r = normalize_or_zero(cross(f, up));
  const Vec3d d = cross(f, r);  // image y runs down
  const Vec3d rows[3] = {r, d, f};
  for (int i = 0; i < 3; ++i) {
    c.R.m[i][0] = rows[i].x;
    c.R.m[i][1] = rows[i].y;
    c.R.m[i][2] = rows[i].z;
  }
  c.t = -(c.R * eye);
  c.source = "test";
  return c;
}

// The half-plane {p : (p − origin)·normal = 0, 0 <= (p − origin)·extent <= length}
// (a strip when length is finite).
struct HalfPlane {
  Vec3d origin, normal, extent;
  double length = std::numeric_limits<double>::infinity();
};

inline GBuffer ray_cast(const Camera& cam, const std::vector<HalfPlane>& planes) {
  GBuffer g;
  g.width = cam.width;
  g.height = cam.height;
  g.depth.assign(g.pixels(), 1e10f);
  g.normal.assign(g.pixels(), Vec3{});
  const Vec3d eye = cam.centre();
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      // View ray with z = 1, so the ray parameter is the planar depth.
      const Vec3d dv{(x + 0.5 - cam.cx) / cam.fx, (y + 0.5 - cam.cy) / cam.fy, 1.0};
      const Vec3d dw = cam.view_dir_to_world(dv);
      double best = std::numeric_limits<double>::infinity();
      Vec3d best_n;
      for (const HalfPlane& p : planes) {
        const double denom = dot(dw, p.normal);
        if (std::fabs(denom) < 1e-12) continue;
        const double t = dot(p.origin - eye, p.normal) / denom;
        if (!(t > 1e-6) || t >= best) continue;
        const double along = dot(eye + dw * t - p.origin, p.extent);
        if (along < 0 || along > p.length) continue;
        best = t;
        best_n = denom < 0 ? p.normal : -p.normal;  // facing the camera
      }
      if (std::isfinite(best)) {
        g.depth[size_t(y) * g.width + x] = float(best);
        g.normal[size_t(y) * g.width + x] = Vec3(best_n);
      }
    }
  return g;
}

// A V-groove of opening angle gamma (radians) with its crease on the world x axis: face A is
// the floor {z = 0, y >= 0}, face B leaves the crease in direction (0, cos γ, sin γ) for
// `length_b` (infinite by default).
inline std::vector<HalfPlane> v_groove(double gamma,
                                       double length_b = std::numeric_limits<double>::infinity()) {
  return {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},
          {{0, 0, 0},
           {0, std::sin(gamma), -std::cos(gamma)},
           {0, std::cos(gamma), std::sin(gamma)},
           length_b}};
}

// The right-angled groove with a unit-wide wall (v_groove(π/2, 1)) seen from 2.5 along its
// bisector, the view turned by yaw_deg about world z through the eye; DiffCol 0.8 everywhere,
// DiffDir 1 on the wall, 0 on the floor: the lit-wall scene of the temporal tests.
inline GBuffer lit_groove(Camera& cam, double yaw_deg, int w, int h, double fov_deg) {
  const Vec3d bisector{0, std::cos(M_PI / 4), std::sin(M_PI / 4)};
  const Vec3d eye = bisector * 2.5, look = bisector * 0.4 - eye;
  const double a = yaw_deg * M_PI / 180;
  const Vec3d turned{look.x * std::cos(a) - look.y * std::sin(a),
                     look.x * std::sin(a) + look.y * std::cos(a), look.z};
  cam = look_at(w, h, fov_deg, eye, eye + turned);
  GBuffer g = ray_cast(cam, v_groove(M_PI / 2, 1.0));
  g.diffcol.assign(g.pixels(), Vec3{0.8f, 0.8f, 0.8f});
  g.diffdir.assign(g.pixels(), Vec3{});
  for (size_t i = 0; i < g.pixels(); ++i)
    if (g.depth[i] < 1e9f && g.normal[i].z < 0.99f) g.diffdir[i] = Vec3{1, 1, 1};
  return g;
}

// A V-groove of 75 degrees with a slanted occluder, seen at an odd resolution (partial 4x4
// blocks): the scene of the thread-determinism tests.
inline GBuffer busy_scene(Camera& cam) {
  cam = look_at(131, 77, 60, {0.4, 2.0, 1.5}, {0, 0, 0.2});
  std::vector<HalfPlane> planes = v_groove(75 * M_PI / 180);
  planes.push_back({{0.3, 0.5, 0.1}, {0.6, 0.0, 0.8}, {0, 0, 1}});  // a slanted occluder
  return ray_cast(cam, planes);
}

}  // namespace hbil::test
