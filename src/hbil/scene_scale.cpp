// scene_scale.cpp: see scene_scale.h.
#include "hbil/scene_scale.h"

#include <algorithm>
#include <cstdio>
#include <vector>

namespace hbil {

SceneScale measure_scene(const GBuffer& g, const Camera& cam, const Params& p) {
  std::vector<float> z;
  const size_t n = size_t(g.width) * size_t(g.height);
  z.reserve(n);
  if (!g.depth.empty()) {
    for (size_t i = 0; i < n; ++i)
      if (g.depth[i] < p.background_depth) z.push_back(g.depth[i]);
  } else if (!g.position.empty()) {
    for (size_t i = 0; i < n; ++i) {
      const Vec3& w = g.position[i];
      const double vz = cam.R.m[2][0] * w.x + cam.R.m[2][1] * w.y + cam.R.m[2][2] * w.z + cam.t.z;
      if (vz > 0 && vz < p.background_depth) z.push_back(float(vz));
    }
  }
  SceneScale s;
  s.geometry = z.size();
  if (z.empty()) return s;
  auto at = [&](double q) {
    const size_t k = std::min(z.size() - 1, size_t(q * double(z.size() - 1) + 0.5));
    std::nth_element(z.begin(), z.begin() + std::ptrdiff_t(k), z.end());
    return double(z[k]);
  };
  s.depth_p10 = at(0.1);
  s.depth_median = at(0.5);
  s.depth_p90 = at(0.9);
  s.width_at_median = double(g.width) * s.depth_median / cam.fx;
  return s;
}

Params resolve_scene_params(const Params& p, const SceneScale& s, std::string* why) {
  Params r = p;
  if (why) why->clear();
  if (!p.gather_radius_auto && !p.thickness_auto && !p.gather_thickness_auto) return r;
  r.gather_radius_auto = r.thickness_auto = r.gather_thickness_auto = false;
  std::string text;
  char line[256];
  auto say = [&](const char* fmt, double v) {
    std::snprintf(line, sizeof line, fmt, v);
    text += (text.empty() ? "" : ", ") + std::string(line);
  };
  const bool measured = s.geometry > 0;
  const double thick = kAutoThickness * s.depth_median;
  if (p.gather_radius_auto) {
    if (measured) r.gather_radius = s.width_at_median;
    say(measured ? "gather_radius %.3g (the frame's width at the median depth)"
                 : "gather_radius %.3g (no geometry in the first frame)",
        r.gather_radius);
  }
  if (p.thickness_auto) {
    if (measured) r.thickness = std::min(thick, kAutoThicknessOfRadius * p.radius);
    say(measured ? "thickness %.3g (0.15 x the median depth, at most 0.4 x radius)"
                 : "thickness %.3g (no geometry in the first frame)",
        r.thickness);
  }
  if (p.gather_thickness_auto) {
    // With thickness given, the gather's samples keep it, as before there were two.
    r.gather_thickness =
        p.thickness_auto && measured ? kAutoGatherThickness * s.depth_median : r.thickness;
    say(p.thickness_auto && measured ? "gather_thickness %.3g (0.3 x the median depth)"
                                     : "gather_thickness %.3g (= thickness)",
        r.gather_thickness);
  }
  if (measured) {
    std::snprintf(line, sizeof line, "; median depth %.3g (10-90 %%: %.3g-%.3g)", s.depth_median,
                  s.depth_p10, s.depth_p90);
    text += line;
  }
  if (why) *why = text;
  return r;
}

}  // namespace hbil
