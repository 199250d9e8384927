// ao_frame.cpp: see ao_frame.h.
#include "hbil/ao_frame.h"

#include <tbb/parallel_for.h>

#include "hbil/interleave.h"
#include "hbil/spatial_filter.h"

namespace hbil {

AoFrame compute_ao_frame(const GBuffer& g, const Camera& cam, const Params& p) {
  return compute_ao_frame(make_view_gbuffer(g, cam, p), g.normal, cam, p);
}

AoFrame compute_ao_frame(const ViewGBuffer& v, const std::vector<Vec3>& world_normal,
                         const Camera& cam, const Params& p) {
  const HorizonConfig c = make_horizon_config(p, cam);
  HorizonImage h =
      p.interleave ? horizon_interleaved(v, c, p.slices) : horizon_full(v, c, p.slices);
  if (p.interleave && p.spatial_filter) h = spatial_filter(v, h, float(p.depth_tolerance));

  AoFrame out;
  out.width = v.width;
  out.height = v.height;
  out.ao.assign(v.pixels(), 1.f);
  out.cone_cos.assign(v.pixels(), 0.f);
  out.bent.assign(v.pixels(), Vec3{});
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (!world_normal.empty()) out.bent[i] = world_normal[i];
      if (v.is_background(i)) continue;
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
