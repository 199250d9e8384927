// gbuffer_simd.cpp: make_view_gbuffer's rows (gbuffer.cpp) from a depth pass, one pixel per
// SIMD lane (Google Highway, the widest instruction set of the machine chosen at run time; as
// many lanes as its vector holds doubles, for the view transform is in double). Every lane
// does the scalar loop's arithmetic in its order, without fused multiply-adds (the file is
// compiled with -ffp-contract=off), so the view-space G-buffer is the scalar one to the bit
// (tests/gbuffer_test.cpp). All the fields are read and written in runs of memory: no gathers.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "hbil/gbuffer_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/highway.h>

#include "hbil/gbuffer.h"

HWY_BEFORE_NAMESPACE();
namespace hbil::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

int ViewRowFromDepth(const GBuffer& g, const Camera& cam, double background_depth, int y,
                     ViewGBuffer& v) {
  const hn::ScalableTag<double> dd;
  const hn::Rebind<float, decltype(dd)> df;
  using VD = hn::Vec<decltype(dd)>;
  using VF = hn::Vec<decltype(df)>;
  const int n = int(hn::Lanes(dd));
  const bool alpha = !g.alpha.empty(), back = !g.backdepth.empty();
  const VD zero = hn::Zero(dd), bg = hn::Set(dd, background_depth);
  const VD cx = hn::Set(dd, cam.cx), fx = hn::Set(dd, cam.fx);
  // The row's (v − cy) / fy of cam.unproject(u, v, z), v = y + 0.5: the same for every lane.
  const VD ry =
      hn::Div(hn::Sub(hn::Set(dd, double(y) + 0.5), hn::Set(dd, cam.cy)), hn::Set(dd, cam.fy));
  const VD margin = hn::Set(dd, 1.001);
  const VF zero_f = hn::Zero(df), background_f = hn::Set(df, ViewGBuffer::kBackground);
  const VF no_thickness = hn::Set(df, -1.f);
  // cam.R * d, row r, in Mat3d's order.
  auto row = [&](int r, VD x, VD yv, VD z) {
    return hn::Add(
        hn::Add(hn::Mul(hn::Set(dd, cam.R.m[r][0]), x), hn::Mul(hn::Set(dd, cam.R.m[r][1]), yv)),
        hn::Mul(hn::Set(dd, cam.R.m[r][2]), z));
  };
  // (Masks of doubles and of floats differ in size: through a vector of 0 and 1.)
  auto to_float_mask = [&](auto m) {
    return hn::Gt(hn::DemoteTo(df, hn::IfThenElseZero(m, hn::Set(dd, 1.0))), zero_f);
  };
  int x = 0;
  for (; x + n <= g.width; x += n) {
    const size_t i = size_t(y) * g.width + x;
    VF wx, wy, wz;
    hn::LoadInterleaved3(df, &g.normal[i].x, wx, wy, wz);
    const VD ax = hn::PromoteTo(dd, wx), ay = hn::PromoteTo(dd, wy), az = hn::PromoteTo(dd, wz);
    const VD dx = row(0, ax, ay, az), dy = row(1, ax, ay, az), dz = row(2, ax, ay, az);
    // normalize_or_zero
    const VD l = hn::Sqrt(hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz)));
    const auto unit = hn::And(hn::Gt(l, zero), hn::IsFinite(l));
    const VD nx = hn::IfThenElseZero(unit, hn::Div(dx, l));
    const VD ny = hn::IfThenElseZero(unit, hn::Div(dy, l));
    const VD nz = hn::IfThenElseZero(unit, hn::Div(dz, l));
    const auto no_normal = hn::And(hn::And(hn::Eq(nx, zero), hn::Eq(ny, zero)), hn::Eq(nz, zero));
    const VD z = hn::PromoteTo(dd, hn::LoadU(df, &g.depth[i]));
    auto ok = hn::AndNot(no_normal, hn::Lt(z, bg));
    if (alpha) {
      const VD a = hn::PromoteTo(dd, hn::LoadU(df, &g.alpha[i]));
      ok = hn::And(ok, hn::Gt(a, zero));
    }
    // cam.unproject(x + 0.5, y + 0.5, z)
    const VD u = hn::Add(hn::Iota(dd, double(x)), hn::Set(dd, 0.5));
    const VD px = hn::Mul(hn::Div(hn::Sub(u, cx), fx), z);
    const VD py = hn::Mul(ry, z);
    const auto ok_f = to_float_mask(ok);
    hn::StoreInterleaved3(hn::IfThenElseZero(ok_f, hn::DemoteTo(df, px)),
                          hn::IfThenElseZero(ok_f, hn::DemoteTo(df, py)),
                          hn::IfThenElse(ok_f, hn::DemoteTo(df, z), background_f), df,
                          &v.position[i].x);
    hn::StoreInterleaved3(hn::IfThenElseZero(ok_f, hn::DemoteTo(df, nx)),
                          hn::IfThenElseZero(ok_f, hn::DemoteTo(df, ny)),
                          hn::IfThenElseZero(ok_f, hn::DemoteTo(df, nz)), df, &v.normal[i].x);
    if (back) {
      // length(pv) * (zb − zf) / zf where zb < background_depth and zb > zf * 1.001.
      const VD zb = hn::PromoteTo(dd, hn::LoadU(df, &g.backdepth[i]));
      const auto thick = hn::And(ok, hn::And(hn::Lt(zb, bg), hn::Gt(zb, hn::Mul(z, margin))));
      const VD len = hn::Sqrt(hn::Add(hn::Add(hn::Mul(px, px), hn::Mul(py, py)), hn::Mul(z, z)));
      const VD t = hn::Div(hn::Mul(len, hn::Sub(zb, z)), z);
      hn::StoreU(hn::IfThenElse(to_float_mask(thick), hn::DemoteTo(df, t), no_thickness), df,
                 &v.thickness[i]);
    }
  }
  return x;
}

}  // namespace hbil::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hbil {
HWY_EXPORT(ViewRowFromDepth);

int view_row_from_depth(const GBuffer& g, const Camera& cam, double background_depth, int y,
                        ViewGBuffer& v) {
  return HWY_DYNAMIC_DISPATCH(ViewRowFromDepth)(g, cam, background_depth, y, v);
}
}  // namespace hbil
#endif
