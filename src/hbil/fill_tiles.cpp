// fill_tiles.cpp: see fill_tiles.h.
#include "hbil/fill_tiles.h"

#include <algorithm>
#include <cmath>

namespace hbil {

float FillTiles::at(const Vec3d& p) const {
  double sum = 0, weights = 0;
  for (const View& v : views) {
    if (v.cols <= 0 || v.rows <= 0 || !(v.w > 0) || !(v.h > 0) || !(v.weight > 0)) continue;
    const Vec3d q = v.cam.world_to_view(p);
    if (!(q.z > 0)) continue;
    double u, r;
    v.cam.project(q, u, r);
    // Tile coordinates, tile centres at integers; outside the display window: not seen.
    const double tx = (u - v.x0) / v.w * v.cols - 0.5, ty = (r - v.y0) / v.h * v.rows - 0.5;
    if (!(tx >= -0.5 && tx <= v.cols - 0.5 && ty >= -0.5 && ty <= v.rows - 0.5)) continue;
    const double cx = std::clamp(tx, 0.0, double(v.cols - 1)),
                 cy = std::clamp(ty, 0.0, double(v.rows - 1));
    const int x0 = std::min(int(cx), v.cols - 1), y0 = std::min(int(cy), v.rows - 1);
    const int x1 = std::min(x0 + 1, v.cols - 1), y1 = std::min(y0 + 1, v.rows - 1);
    const double fx = cx - x0, fy = cy - y0;
    auto f = [&](int x, int y) { return double(v.factor[size_t(y) * size_t(v.cols) + size_t(x)]); };
    const double k = (f(x0, y0) * (1 - fx) + f(x1, y0) * fx) * (1 - fy) +
                     (f(x0, y1) * (1 - fx) + f(x1, y1) * fx) * fy;
    sum += v.weight * k;
    weights += v.weight;
  }
  return weights > 0 ? float(sum / weights) : 1.f;
}

}  // namespace hbil
