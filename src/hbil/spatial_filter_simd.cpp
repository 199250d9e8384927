// spatial_filter_simd.cpp: spatial_filter's pixels (spatial_filter.cpp) for runs of a row
// whose 4x4 windows lie inside the columns, one pixel per SIMD lane (Google Highway, the
// widest instruction set of the machine chosen at run time). Every lane adds its neighbours
// in the scalar loop's order with the scalar arithmetic and no fused multiply-adds (the file
// is compiled with -ffp-contract=off), so the results are the scalar ones to the bit
// (tests/spatial_filter_test.cpp): a neighbour that fails the same-surface test is a lane
// left as it was, not a weight of 0.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "hbil/spatial_filter_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/highway.h>

#include "hbil/spatial_filter.h"

HWY_BEFORE_NAMESPACE();
namespace hbil::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

int FilterRun(const ViewGBuffer& g, const HorizonImage& in, float depth_tolerance, int y, int x0,
              int count, HorizonImage& out) {
  const hn::ScalableTag<float> d;
  using V = hn::Vec<decltype(d)>;
  const int n = int(hn::Lanes(d));
  const bool has_e = !in.irradiance.empty(), has_occ = !in.ao.empty();
  const V background = hn::Set(d, ViewGBuffer::kBackground), cos_min = hn::Set(d, 0.8f);
  const V one = hn::Set(d, 1.f), zero = hn::Zero(d), dtol = hn::Set(d, depth_tolerance);
  auto load3 = [&](const Vec3* p, V& a, V& b, V& c) { hn::LoadInterleaved3(d, &p->x, a, b, c); };
  int x = x0;
  for (; x + n <= x0 + count; x += n) {
    const size_t c = size_t(y) * g.width + x;
    V px, py, pz, nx, ny, nz;
    load3(&g.position[c], px, py, pz);
    const auto centre = hn::Lt(pz, background);  // !is_background
    if (hn::AllFalse(d, centre)) continue;
    load3(&g.normal[c], nx, ny, nz);
    const V tol = hn::Mul(dtol, pz);
    V ao = zero, vis = zero, w = zero, bx = zero, by = zero, bz = zero, ex = zero, ey = zero,
      ez = zero;
    for (int yy = y - 1; yy <= y + 2; ++yy) {
      if (yy < 0 || yy >= g.height) continue;
      for (int dx = -1; dx <= 2; ++dx) {
        const size_t k = size_t(yy) * g.width + x + dx;
        V qx, qy, qz, mx, my, mz;
        load3(&g.position[k], qx, qy, qz);
        load3(&g.normal[k], mx, my, mz);
        // same_surface: |dot(Q − P, n)| <= tol and dot(m, n) >= 0.8, Q not background.
        const V plane = hn::Add(hn::Add(hn::Mul(hn::Sub(qx, px), nx), hn::Mul(hn::Sub(qy, py), ny)),
                                hn::Mul(hn::Sub(qz, pz), nz));
        const V facing = hn::Add(hn::Add(hn::Mul(mx, nx), hn::Mul(my, ny)), hn::Mul(mz, nz));
        const auto ok = hn::And(hn::Lt(qz, background),
                                hn::And(hn::Le(hn::Abs(plane), tol), hn::Ge(facing, cos_min)));
        if (hn::AllFalse(d, ok)) continue;
        auto add = [&](V& acc, V v) { acc = hn::IfThenElse(ok, hn::Add(acc, v), acc); };
        V b0, b1, b2;
        if (has_occ) {
          add(ao, hn::LoadU(d, &in.ao[k]));
          add(vis, hn::LoadU(d, &in.vis[k]));
          load3(&in.bent[k], b0, b1, b2);
          add(bx, b0), add(by, b1), add(bz, b2);
        }
        if (has_e) {
          load3(&in.irradiance[k], b0, b1, b2);
          add(ex, b0), add(ey, b1), add(ez, b2);
        }
        add(w, one);
      }
    }
    // HorizonMean::store; background lanes keep what `out` holds (the input's values).
    const V inv = hn::Div(one, hn::IfThenElse(centre, w, one));
    auto keep = [&](V v, V old) { return hn::IfThenElse(centre, hn::Mul(v, inv), old); };
    V o0, o1, o2;
    if (has_occ) {
      hn::StoreU(keep(ao, hn::LoadU(d, &out.ao[c])), d, &out.ao[c]);
      hn::StoreU(keep(vis, hn::LoadU(d, &out.vis[c])), d, &out.vis[c]);
      load3(&out.bent[c], o0, o1, o2);
      hn::StoreInterleaved3(keep(bx, o0), keep(by, o1), keep(bz, o2), d, &out.bent[c].x);
    }
    if (has_e) {
      load3(&out.irradiance[c], o0, o1, o2);
      hn::StoreInterleaved3(keep(ex, o0), keep(ey, o1), keep(ez, o2), d, &out.irradiance[c].x);
    }
  }
  return x - x0;
}

}  // namespace hbil::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hbil {
HWY_EXPORT(FilterRun);

int spatial_filter_run(const ViewGBuffer& g, const HorizonImage& in, float depth_tolerance, int y,
                       int x0, int count, HorizonImage& out) {
  return HWY_DYNAMIC_DISPATCH(FilterRun)(g, in, depth_tolerance, y, x0, count, out);
}
}  // namespace hbil
#endif
