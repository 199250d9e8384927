// gbuffer.cpp: G-buffer to view space.
#include "hbil/gbuffer.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace hbil {

std::vector<Vec3>* GBuffer::rgb(const std::string& field) {
  if (field == "normal") return &normal;
  if (field == "position") return &position;
  if (field == "diffcol") return &diffcol;
  if (field == "diffdir") return &diffdir;
  if (field == "emit") return &emit;
  if (field == "f0") return &f0;
  if (field == "env") return &env;
  if (field == "glosscol") return &glosscol;
  if (field == "glossdir") return &glossdir;
  if (field == "glossind") return &glossind;
  if (field == "transcol") return &transcol;
  if (field == "transdir") return &transdir;
  if (field == "transind") return &transind;
  return nullptr;
}

ViewGBuffer make_view_gbuffer(const GBuffer& g, const Camera& cam, const Params& p) {
  ViewGBuffer v;
  v.width = g.width;
  v.height = g.height;
  v.position.assign(g.pixels(), Vec3{0, 0, ViewGBuffer::kBackground});
  v.normal.assign(g.pixels(), Vec3{});
  const bool from_depth = !g.depth.empty();
  const bool back = !g.backdepth.empty();
  if (back) v.thickness.assign(g.pixels(), -1.f);
  tbb::parallel_for(0, g.height, [&](int y) {
    for (int x = 0; x < g.width; ++x) {
      const size_t i = size_t(y) * g.width + x;
      if (!g.alpha.empty() && !(g.alpha[i] > 0.f)) continue;
      const Vec3d n = normalize_or_zero(cam.world_dir_to_view(Vec3d(g.normal[i])));
      if (n.x == 0 && n.y == 0 && n.z == 0) continue;
      Vec3d pv;
      if (from_depth) {
        if (!(g.depth[i] < p.background_depth)) continue;
        pv = cam.unproject(x + 0.5, y + 0.5, g.depth[i]);
      } else {
        const Vec3& w = g.position[i];
        if (w.x == 0 && w.y == 0 && w.z == 0) continue;  // Blender background
        pv = cam.world_to_view(Vec3d(w));
        if (!(pv.z > 0) || !(pv.z < p.background_depth)) continue;
      }
      v.position[i] = Vec3(pv);
      v.normal[i] = Vec3(n);
      if (back) {
        const double zb = g.backdepth[i], zf = pv.z;
        if (zb < p.background_depth && zb > zf * 1.001)
          v.thickness[i] = float(length(pv) * (zb - zf) / zf);
      }
    }
  });
  return v;
}

}  // namespace hbil
