// spatial_filter.cpp: see spatial_filter.h.
#include "hbil/spatial_filter.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace hbil {

namespace {
constexpr float kNormalCos = 0.8f;
}

HorizonImage spatial_filter(const ViewGBuffer& g, const HorizonImage& in, float depth_tolerance) {
  HorizonImage out = in;
  tbb::parallel_for(0, g.height, [&](int y) {
    for (int x = 0; x < g.width; ++x) {
      const size_t c = size_t(y) * g.width + x;
      if (g.is_background(c)) continue;
      const Vec3& P = g.position[c];
      const Vec3& n = g.normal[c];
      const float tol = depth_tolerance * P.z;
      float ao = 0, vis = 0, w = 0;
      Vec3 bent, irr;
      const bool gather = !in.irradiance.empty();
      for (int yy = y - 1; yy <= y + 2; ++yy) {
        if (yy < 0 || yy >= g.height) continue;
        for (int xx = x - 1; xx <= x + 2; ++xx) {
          if (xx < 0 || xx >= g.width) continue;
          const size_t k = size_t(yy) * g.width + xx;
          if (g.is_background(k)) continue;
          if (std::fabs(dot(g.position[k] - P, n)) > tol || dot(g.normal[k], n) < kNormalCos)
            continue;
          ao += in.ao[k];
          vis += in.vis[k];
          bent += in.bent[k];
          if (gather) irr += in.irradiance[k];
          w += 1.f;
        }
      }
      // w >= 1: the centre pixel always passes its own test.
      const float inv = 1.f / w;  // one division, not eight
      out.ao[c] = ao * inv;
      out.vis[c] = vis * inv;
      out.bent[c] = bent * inv;
      if (gather) out.irradiance[c] = irr * inv;
    }
  });
  return out;
}

}  // namespace hbil
