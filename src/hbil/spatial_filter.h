// spatial_filter.h: re-interleave filter. After the 4x4 interleaved search each pixel holds
// only its own `slices` directions; averaging the 4x4 window around it (offsets -1..2, which
// holds each of the 16 phases exactly once) over pixels of the same surface makes every
// pixel integrate all 16 x slices directions. HBIL §3.3 leaves this "bilateral recomposition"
// as future work and relies on TAA instead; a compositing tool must give a usable single
// frame, so we do it here.
//
// Same surface: the neighbour lies within depth_tolerance * z of the centre pixel's tangent
// plane (a plane distance, not a depth difference, so grazing floors are kept) and its
// normal is within acos(0.8) ~ 37 degrees of the centre's. Weights are 0 or 1.
#pragma once

#include <algorithm>
#include <cmath>

#include "hbil/gbuffer.h"
#include "hbil/interleave.h"

namespace hbil {

// The same-surface test of the filter (and of the reduced search's upsample, reduced.h): the
// point Q with normal m lies within `tol` of the tangent plane of (P, n) and m is within
// acos(0.8) of n.
inline bool same_surface(const Vec3& P, const Vec3& n, const Vec3& Q, const Vec3& m, float tol) {
  return std::fabs(dot(Q - P, n)) <= tol && dot(m, n) >= 0.8f;
}

// The mean of value(p) over the pixels p of v in the window [x0, x1] x [y0, y1] (clipped
// to v) that lie on the surface (P, n) of `tol` (same_surface), each with weight 1; `own`
// where none does (a degenerate normal fails even its own pixel's test). For the reduced
// search's radiance (reduced.h) and the escape pass (unseen.h).
template <class T, class Value>
T surface_mean(const ViewGBuffer& v, int x0, int y0, int x1, int y1, const Vec3& P, const Vec3& n,
               float tol, Value value, T own) {
  T sum{};
  float w = 0;
  for (int y = std::max(0, y0); y <= std::min(v.height - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(v.width - 1, x1); ++x) {
      const size_t p = size_t(y) * v.width + x;
      if (v.is_background(p) || !same_surface(P, n, v.position[p], v.normal[p], tol)) continue;
      sum += value(p);
      w += 1.f;
    }
  return w > 0 ? sum / w : own;
}

// `vectorised`: the pixels whose windows lie inside the columns run one per SIMD lane
// (spatial_filter_simd.cpp; the same results to the bit); false: all by the scalar loop.
HorizonImage spatial_filter(const ViewGBuffer& g, const HorizonImage& in, float depth_tolerance,
                            bool vectorised = true);

// spatial_filter_simd.cpp: pixels x0 .. x0 + count − 1 of row y, as many as fill whole SIMD
// vectors (the number done, from x0), into `out` (a copy of `in`); needs x0 >= 1 and
// x0 + count + 2 <= g.width.
int spatial_filter_run(const ViewGBuffer& g, const HorizonImage& in, float depth_tolerance, int y,
                       int x0, int count, HorizonImage& out);

}  // namespace hbil
