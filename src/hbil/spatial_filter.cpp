// spatial_filter.cpp: see spatial_filter.h.
#include "hbil/spatial_filter.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace hbil {

HorizonImage spatial_filter(const ViewGBuffer& g, const HorizonImage& in, float depth_tolerance,
                            bool vectorised) {
  HorizonImage out = in;
  tbb::parallel_for(0, g.height, [&](int y) {
    // Columns 1 .. width − 3 have their whole window inside the row: those the SIMD run
    // takes (whole vectors of them) are skipped below.
    int simd_from = g.width, simd_to = g.width;
    if (vectorised && g.width >= 4) {
      simd_from = 1;
      simd_to = 1 + spatial_filter_run(g, in, depth_tolerance, y, 1, g.width - 3, out);
    }
    for (int x = 0; x < g.width; ++x) {
      if (x == simd_from) x = simd_to;
      if (x >= g.width) break;
      const size_t c = size_t(y) * g.width + x;
      if (g.is_background(c)) continue;
      const Vec3& P = g.position[c];
      const Vec3& n = g.normal[c];
      const float tol = depth_tolerance * P.z;
      HorizonMean mean;
      for (int yy = y - 1; yy <= y + 2; ++yy) {
        if (yy < 0 || yy >= g.height) continue;
        for (int xx = x - 1; xx <= x + 2; ++xx) {
          if (xx < 0 || xx >= g.width) continue;
          const size_t k = size_t(yy) * g.width + xx;
          if (g.is_background(k) || !same_surface(P, n, g.position[k], g.normal[k], tol)) continue;
          mean.add(in, k, 1.f);
        }
      }
      mean.store(out, c);  // w >= 1: the centre pixel always passes its own test
    }
  });
  return out;
}

}  // namespace hbil
