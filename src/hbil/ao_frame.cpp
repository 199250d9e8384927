// ao_frame.cpp: see ao_frame.h.
#include "hbil/ao_frame.h"

#include <tbb/parallel_for.h>

#include "hbil/interleave.h"
#include "hbil/spatial_filter.h"

namespace hbil {

std::vector<Vec3> source_radiance(const GBuffer& g, const std::vector<Vec3>& irradiance) {
  std::vector<Vec3> L(g.pixels());
  for (size_t i = 0; i < g.pixels(); ++i) {
    const Vec3 e = irradiance.empty() ? g.diffdir[i] : g.diffdir[i] + irradiance[i];
    L[i] = Vec3{g.diffcol[i].x * e.x, g.diffcol[i].y * e.y, g.diffcol[i].z * e.z};
    if (!g.emit.empty()) L[i] += g.emit[i];
  }
  return L;
}

AoFrame compute_ao_frame(const GBuffer& g, const Camera& cam, const Params& p) {
  return compute_ao_frame(make_view_gbuffer(g, cam, p), g, cam, p);
}

AoFrame compute_ao_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam,
                         const Params& p) {
  const std::vector<Vec3>& world_normal = g.normal;
  const HorizonConfig c = make_horizon_config(p, cam);
  const bool gather = p.wants("irradiance") || p.wants("indirect");
  auto search = [&](const std::vector<Vec3>* radiance) {
    HorizonImage h = p.interleave ? horizon_interleaved(v, c, p.slices, radiance)
                                  : horizon_full(v, c, p.slices, radiance);
    if (p.interleave && p.spatial_filter) h = spatial_filter(v, h, float(p.depth_tolerance));
    return h;
  };
  // Bounce k gathers the outgoing radiance of bounce k − 1 (bounce 0: direct light and
  // emission). Occlusion is the same every time; the last search's is kept.
  HorizonImage h;
  std::vector<Vec3> irradiance;
  for (int bounce = 0; bounce < (gather ? p.bounces : 1); ++bounce) {
    const std::vector<Vec3> L = gather ? source_radiance(g, irradiance) : std::vector<Vec3>{};
    h = search(gather ? &L : nullptr);
    irradiance = h.irradiance;
  }

  AoFrame out;
  out.width = v.width;
  out.height = v.height;
  out.ao.assign(v.pixels(), 1.f);
  out.cone_cos.assign(v.pixels(), 0.f);
  out.bent.assign(v.pixels(), Vec3{});
  if (gather) {
    out.irradiance.assign(v.pixels(), Vec3{});
    out.indirect.assign(v.pixels(), Vec3{});
  }
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (!world_normal.empty()) out.bent[i] = world_normal[i];
      if (v.is_background(i)) continue;
      if (gather) {
        const Vec3 e = h.irradiance[i], a = g.diffcol[i];
        out.irradiance[i] = e;
        out.indirect[i] = Vec3{a.x * e.x, a.y * e.y, a.z * e.z};
      }
      out.ao[i] = std::clamp(h.ao[i], 0.f, 1.f);
      out.cone_cos[i] = std::clamp(1.f - h.vis[i], 0.f, 1.f);  // eq. 12
      const Vec3 b = Vec3(normalize_or_zero(cam.view_dir_to_world(Vec3d(h.bent[i]))));
      // Fully occluded: no bent direction; fall back to the (unit) normal.
      out.bent[i] =
          dot(b, b) > 0 ? b : Vec3(normalize_or_zero(cam.view_dir_to_world(Vec3d(v.normal[i]))));
    }
  });
  return out;
}

}  // namespace hbil
