// march_simd-inl.h: what the two SIMD marches (march_bitmask_simd.cpp, march_horizon_simd.cpp)
// share, one pixel per lane: the lane types and vector helpers, and the lane forms of
// march_common.h's pixel frame, slice line and step. Every function does the scalar
// reference's arithmetic in the same order, without fused multiply-adds (the including files
// are compiled with -ffp-contract=off), so the marches keep the scalar results to the bit.
//
// Included once per Highway target from inside a foreach_target compilation (the guard
// toggles with HWY_TARGET_TOGGLE, as Highway's own -inl.h headers do).
#if defined(HBIL_MARCH_SIMD_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef HBIL_MARCH_SIMD_INL_H_
#undef HBIL_MARCH_SIMD_INL_H_
#else
#define HBIL_MARCH_SIMD_INL_H_
#endif

#include <hwy/highway.h>

#include <bit>
#include <cmath>
#include <cstdint>

#include "hbil/gbuffer.h"
#include "hbil/march.h"
#include "hbil/march_common.h"

HWY_BEFORE_NAMESPACE();
namespace hbil::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
namespace simd {

using DF = hn::ScalableTag<float>;
using DI = hn::RebindToSigned<DF>;
using DU = hn::RebindToUnsigned<DF>;
using VF = hn::Vec<DF>;
using VI = hn::Vec<DI>;
using VU = hn::Vec<DU>;
using MF = hn::Mask<DF>;
constexpr size_t kMaxLanes = HWY_MAX_BYTES / sizeof(float);

// The Vec3 of march_common.h, one per lane.
struct V3 {
  VF x, y, z;
};
HWY_INLINE VF Dot(const V3& a, const V3& b) {
  return hn::Add(hn::Add(hn::Mul(a.x, b.x), hn::Mul(a.y, b.y)), hn::Mul(a.z, b.z));
}
HWY_INLINE V3 Sub3(const V3& a, const V3& b) {
  return {hn::Sub(a.x, b.x), hn::Sub(a.y, b.y), hn::Sub(a.z, b.z)};
}
HWY_INLINE V3 Add3(const V3& a, const V3& b) {
  return {hn::Add(a.x, b.x), hn::Add(a.y, b.y), hn::Add(a.z, b.z)};
}
HWY_INLINE V3 Scale(const V3& a, VF s) {
  return {hn::Mul(a.x, s), hn::Mul(a.y, s), hn::Mul(a.z, s)};
}
HWY_INLINE V3 Select(MF m, const V3& a, const V3& b) {
  return {hn::IfThenElse(m, a.x, b.x), hn::IfThenElse(m, a.y, b.y), hn::IfThenElse(m, a.z, b.z)};
}
HWY_INLINE VF Clamp(VF v, VF lo, VF hi) {
  // std::clamp(v, lo, hi) = v < lo ? lo : (hi < v ? hi : v)
  return hn::IfThenElse(hn::Lt(v, lo), lo, hn::IfThenElse(hn::Lt(hi, v), hi, v));
}
// march::fast_acos at |x| = a, before its reflection for x < 0.
HWY_INLINE VF AcosOfMagnitude(DF d, VF a) {
  VF p = hn::Sub(hn::Set(d, 0.0742610f), hn::Mul(hn::Set(d, 0.0187293f), a));
  p = hn::Add(hn::Set(d, -0.2121144f), hn::Mul(a, p));
  p = hn::Add(hn::Set(d, 1.5707288f), hn::Mul(a, p));
  return hn::Mul(hn::Sqrt(hn::Sub(hn::Set(d, 1.f), a)), p);
}
// march::fast_acos, lane by lane.
HWY_INLINE VF FastAcos(DF d, VF x) {
  const VF r = AcosOfMagnitude(d, hn::Abs(x));
  return hn::IfThenElse(hn::Lt(x, hn::Zero(d)), hn::Sub(hn::Set(d, march::kPi), r), r);
}
// march::fast_atan2, lane by lane.
HWY_INLINE VF FastAtan2(DF d, VF y, VF x) {
  const VF zero = hn::Zero(d);
  const VF ax = hn::Abs(x), ay = hn::Abs(y);
  const VF hi = hn::Max(ax, ay), lo = hn::Min(ax, ay);
  const VF a = hn::IfThenElseZero(hn::Gt(hi, zero), hn::Div(lo, hi)), s = hn::Mul(a, a);
  VF p = hn::Set(d, march::kAtanPoly[0]);
  for (int k = 1; k < 8; ++k) p = hn::Add(hn::Mul(p, s), hn::Set(d, march::kAtanPoly[k]));
  VF r = hn::Mul(a, p);
  r = hn::IfThenElse(hn::Gt(ay, ax), hn::Sub(hn::Set(d, 0.5f * march::kPi), r), r);
  r = hn::IfThenElse(hn::Lt(x, zero), hn::Sub(hn::Set(d, march::kPi), r), r);
  return hn::IfThenElse(hn::Lt(y, zero), hn::Neg(r), r);
}
// normalize_or_zero (vecmath.h).
HWY_INLINE V3 NormalizeOrZero(DF d, const V3& a) {
  const VF l = hn::Sqrt(Dot(a, a));
  const MF ok = hn::And(hn::Gt(l, hn::Zero(d)), hn::Lt(l, hn::Set(d, HUGE_VALF)));
  return {hn::IfThenElseZero(ok, hn::Div(a.x, l)), hn::IfThenElseZero(ok, hn::Div(a.y, l)),
          hn::IfThenElseZero(ok, hn::Div(a.z, l))};
}
HWY_INLINE V3 Gather3(DF d, const Vec3* base, VI idx3) {
  const float* b = &base->x;
  const VI one = hn::Set(DI(), 1);
  return {hn::GatherIndex(d, b, idx3), hn::GatherIndex(d, b + 0, hn::Add(idx3, one)),
          hn::GatherIndex(d, b, hn::Add(idx3, hn::Add(one, one)))};
}
// Each lane's texel k of a SampleView::surface table: the normal n and the plane's
// dot(position, n). Two gathers of 8-byte words, (x, y) and (z, plane), for each half of the
// lanes, split into lanes by their even (low) and odd (high) floats: half the elements a
// gather of each float would load.
HWY_INLINE void GatherSurface(DF d, const std::uint64_t* surface, VI k, V3& n, VF& plane) {
#if HWY_TARGET == HWY_SCALAR
  const std::ptrdiff_t t = hn::GetLane(k);
  auto lo = [](std::uint64_t w) { return std::bit_cast<float>(std::uint32_t(w)); };
  auto hi = [](std::uint64_t w) { return std::bit_cast<float>(std::uint32_t(w >> 32)); };
  n = {hn::Set(d, lo(surface[2 * t])), hn::Set(d, hi(surface[2 * t])),
       hn::Set(d, lo(surface[2 * t + 1]))};
  plane = hn::Set(d, hi(surface[2 * t + 1]));
#else
  const hn::Half<DI> dh;
  const hn::RepartitionToWide<DI> di64;  // half as many 64-bit lanes
  const hn::Rebind<std::uint64_t, decltype(di64)> du64;
  const auto lo = hn::ShiftLeft<1>(hn::PromoteTo(di64, hn::LowerHalf(dh, k)));
  const auto hi = hn::ShiftLeft<1>(hn::PromoteTo(di64, hn::UpperHalf(dh, k)));
  const auto one = hn::Set(di64, 1);
  const VF xy_lo = hn::BitCast(d, hn::GatherIndex(du64, surface, lo));
  const VF xy_hi = hn::BitCast(d, hn::GatherIndex(du64, surface, hi));
  const VF zp_lo = hn::BitCast(d, hn::GatherIndex(du64, surface, hn::Add(lo, one)));
  const VF zp_hi = hn::BitCast(d, hn::GatherIndex(du64, surface, hn::Add(hi, one)));
  n = {hn::ConcatEven(d, xy_hi, xy_lo), hn::ConcatOdd(d, xy_hi, xy_lo),
       hn::ConcatEven(d, zp_hi, zp_lo)};
  plane = hn::ConcatOdd(d, zp_hi, zp_lo);
#endif
}
// march::antiderivative(t, s, c, nx, ny), per lane.
struct Antiderivative {
  VF ao, vis, bx, by;
};
HWY_INLINE Antiderivative AntiderivativeAt(DF d, VF t, VF s, VF c, VF nx, VF ny) {
  const VF one = hn::Set(d, 1.f), half = hn::Set(d, 0.5f);
  const VF a = hn::IfThenElse(hn::Lt(t, hn::Zero(d)), hn::Set(d, -1.f), one);
  const VF sin2 = hn::Mul(hn::Sub(t, hn::Mul(s, c)), half), sincos = hn::Mul(hn::Mul(s, s), half);
  return {hn::Mul(a, hn::Add(hn::Mul(nx, sin2), hn::Mul(ny, sincos))), hn::Mul(a, hn::Sub(one, c)),
          hn::Mul(a, sin2), hn::Mul(a, sincos)};
}
// facing_weight (march_common.h) of n'·(X − P) / |X − P|.
HWY_INLINE VF FacingWeight(DF d, VF n_dot_d3, VF dist) {
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.f);
  VF x = hn::Mul(hn::Sub(hn::Set(d, 0.1f), hn::Div(n_dot_d3, dist)), hn::Set(d, 5.f));
  x = Clamp(x, zero, one);
  return hn::Mul(hn::Mul(x, x), hn::Sub(hn::Set(d, 3.f), hn::Mul(hn::Set(d, 2.f), x)));
}

// The ray f.ray_P + L.dv * (sign * o) * stride of march_common.h, with sign_o = sign * o.
// L.dv.z is 0, so its z term adds a zero to ray_P.z (o and the stride are finite), which
// is therefore the result to the bit, and is not computed: a ray's z is 1. DotRay and
// ScaleRay are Dot and Scale for such a ray, without the product by its z (1 · v = v).
HWY_INLINE VF DotRay(const V3& ray, const V3& v) {
  return hn::Add(hn::Add(hn::Mul(ray.x, v.x), hn::Mul(ray.y, v.y)), v.z);
}
HWY_INLINE V3 ScaleRay(const V3& ray, VF s) {
  return {hn::Mul(ray.x, s), hn::Mul(ray.y, s), s};
}
HWY_INLINE V3 RayAt(const V3& ray_P, const V3& dv, VF sign_o, VF stride) {
  return {hn::Add(ray_P.x, hn::Mul(hn::Mul(dv.x, sign_o), stride)),
          hn::Add(ray_P.y, hn::Mul(hn::Mul(dv.y, sign_o), stride)), ray_P.z};
}

// Lanes = texels i0 + base + lane of row j (march::march_setup and pixel_frame); lanes past
// the run read the run's first texel and, like background texels, are not `valid`.
struct PixelLanes {
  VI ii;     // the lane's texel column
  VI own3;   // 3 x the lane's texel index in the view (SampleView::index)
  MF valid;  // a geometry texel of the run
  V3 P, n, wo, ray_P, e1, e2;
  VF r_tex, rg_tex;
  VF near_span, far_start, far_span;  // step_offset's two groups
  MF tiny;                            // the AO radius is under a texel
  bool far;                           // gather-only samples beyond the AO radius
  float r2, rg2;
  int n_steps;
};
HWY_INLINE PixelLanes LoadPixels(DF d, const SampleView& view, int i0, int j, int base, int count,
                                 const HorizonConfig& c) {
  const DI di;
  PixelLanes px;
  const bool gather = view.radiance != nullptr;
  px.far = gather && c.gather_steps > 0;
  px.r2 = c.radius * c.radius;
  px.rg2 = px.far ? c.gather_radius * c.gather_radius : px.r2;
  px.n_steps = c.steps + (px.far ? c.gather_steps : 0);
  const float focal = 0.5f * (c.fx + c.fy);
  const float diagonal = std::hypot(float(view.width), float(view.height));
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.f);
  const VI lane = hn::Iota(di, 0);
  px.ii = hn::Add(hn::Set(di, i0 + base), lane);
  const MF in_run = hn::RebindMask(d, hn::Lt(lane, hn::Set(di, count - base)));
  const VI i_safe = hn::IfThenElse(hn::RebindMask(di, in_run), px.ii, hn::Set(di, i0));
  const VI own = hn::Add(hn::Mul(hn::Set(di, int(view.row)), hn::Set(di, j)),
                         hn::Mul(i_safe, hn::Set(di, int(view.col))));
  px.own3 = hn::Mul(own, hn::Set(di, 3));
  px.P = Gather3(d, view.position, px.own3);
  px.n = Gather3(d, view.normal, px.own3);
  px.valid = hn::And(in_run, hn::Lt(px.P.z, hn::Set(d, ViewGBuffer::kBackground)));
  const V3& P = px.P;
  px.wo = NormalizeOrZero(d, {hn::Neg(P.x), hn::Neg(P.y), hn::Neg(P.z)});
  px.ray_P = {hn::Div(P.x, P.z), hn::Div(P.y, P.z), one};
  const VF pz_stride = hn::Mul(P.z, hn::Set(d, float(view.stride)));
  px.r_tex = hn::Min(hn::Div(hn::Set(d, c.radius * focal), pz_stride), hn::Set(d, diagonal));
  px.rg_tex = px.far ? hn::Min(hn::Div(hn::Set(d, c.gather_radius * focal), pz_stride),
                               hn::Set(d, diagonal))
                     : px.r_tex;
  const V3& wo = px.wo;
  px.e1 = NormalizeOrZero(d, {hn::Sub(one, hn::Mul(wo.x, wo.x)), hn::Sub(zero, hn::Mul(wo.y, wo.x)),
                              hn::Sub(zero, hn::Mul(wo.z, wo.x))});
  const V3& e1 = px.e1;
  px.e2 = {hn::Sub(hn::Mul(wo.y, e1.z), hn::Mul(wo.z, e1.y)),
           hn::Sub(hn::Mul(wo.z, e1.x), hn::Mul(wo.x, e1.z)),
           hn::Sub(hn::Mul(wo.x, e1.y), hn::Mul(wo.y, e1.x))};
  px.near_span = hn::Sub(px.r_tex, one);
  px.far_start = hn::Max(px.r_tex, one);
  px.far_span = hn::Sub(px.rg_tex, px.r_tex);
  px.tiny = hn::Lt(px.r_tex, one);
  return px;
}
// march::step_offset of step q, per lane.
HWY_INLINE VF StepOffset(DF d, const PixelLanes& px, const HorizonConfig& c, const float* fraction,
                         int q) {
  const VF fq = hn::Set(d, fraction[q]);
  return q < c.steps ? hn::Add(hn::Set(d, 1.f), hn::Mul(px.near_span, fq))
                     : hn::Add(px.far_start, hn::Mul(px.far_span, fq));
}

// march::slice_line for the slice at angle phi; `live`: the lanes whose slice has a line.
struct SliceLanes {
  V3 D, dv;
  VF dx, dy, nx, ny;
  MF live;
};
HWY_INLINE SliceLanes SliceLine(DF d, const PixelLanes& px, const HorizonConfig& c, float phi) {
  const VF zero = hn::Zero(d);
  SliceLanes L;
  const VF cphi = hn::Set(d, std::cos(phi)), sphi = hn::Set(d, std::sin(phi));
  L.D = Add3(Scale(px.e1, cphi), Scale(px.e2, sphi));
  const VF gx = hn::Mul(hn::Set(d, c.fx), hn::Sub(L.D.x, hn::Mul(px.ray_P.x, L.D.z)));
  const VF gy = hn::Mul(hn::Set(d, c.fy), hn::Sub(L.D.y, hn::Mul(px.ray_P.y, L.D.z)));
  const VF gl = hn::Sqrt(hn::Add(hn::Mul(gx, gx), hn::Mul(gy, gy)));
  L.live = hn::And(px.valid, hn::Gt(gl, zero));
  L.dx = hn::Div(gx, gl);
  L.dy = hn::Div(gy, gl);
  L.dv = {hn::Div(L.dx, hn::Set(d, c.fx)), hn::Div(L.dy, hn::Set(d, c.fy)), zero};
  L.nx = Dot(px.n, L.D);
  L.ny = Dot(px.n, px.wo);
  return L;
}

// The integer of a whole float f with |f| <= 2²²: f + 1.5 · 2²³ is exact, in [2²³, 2²⁴],
// and its bits are those of 1.5 · 2²³ plus f. Without ConvertTo's fix-up of out-of-range
// values (four instructions), for values already clamped.
HWY_INLINE VI WholeToInt(DF d, VF f) {
  constexpr float kMagic = 12582912.f;  // 1.5 · 2²³, 0x4B400000
  return hn::Sub(hn::BitCast(DI(), hn::Add(f, hn::Set(d, kMagic))), hn::Set(DI(), 0x4B400000));
}
// march::floor_to_int, lane by lane.
HWY_INLINE VI FloorToInt(DF d, VF v) {
  const VF limit = hn::Set(d, march::kOffsetLimit);
  return WholeToInt(d, hn::Floor(hn::Max(hn::Min(v, limit), hn::Neg(limit))));
}

// march::take_step of step k on one side (sx, sy = ±(dx, dy), sign = ±1). `alive`: the lanes
// not yet past the screen edge, updated. `m` of the result: the lanes whose sample is used.
struct StepLanes {
  MF m;
  VF o;
  VI k_s, k3;  // the sample's texel, and 3 × it (Vec3 floats)
  V3 S, n_s, d3;
  VF dist2;
};
HWY_INLINE StepLanes TakeStep(DF d, const SampleView& view, int j, int k, VF sx, VF sy, VF sign,
                              const PixelLanes& px, const SliceLanes& L, const HorizonConfig& c,
                              const float* fraction, MF& alive) {
  const DI di;
  const VF zero = hn::Zero(d), half = hn::Set(d, 0.5f);
  StepLanes st;
  const bool near = k < c.steps;
  MF m = near ? hn::AndNot(px.tiny, alive) : alive;
  st.o = StepOffset(d, px, c, fraction, k);
  const VI oi = FloorToInt(d, hn::Add(hn::Mul(sx, st.o), half));
  const VI oj = FloorToInt(d, hn::Add(hn::Mul(sy, st.o), half));
  const MF at_p = hn::RebindMask(d, hn::And(hn::Eq(oi, hn::Zero(di)), hn::Eq(oj, hn::Zero(di))));
  m = hn::AndNot(at_p, m);
  const VI si = hn::Add(px.ii, oi), sj = hn::Add(hn::Set(di, j), oj);
  const auto off_i = hn::Or(hn::Lt(si, hn::Zero(di)), hn::Gt(si, hn::Set(di, view.width - 1)));
  const auto off_j = hn::Or(hn::Lt(sj, hn::Zero(di)), hn::Gt(sj, hn::Set(di, view.height - 1)));
  const MF off = hn::And(m, hn::RebindMask(d, hn::Or(off_i, off_j)));
  alive = hn::AndNot(off, alive);
  m = hn::AndNot(off, m);
  st.m = m;
  if (hn::AllFalse(d, m)) return st;
  // (The deinterleaved copies have col = 1: no product for it.)
  const VI col_term = view.col == 1 ? si : hn::Mul(si, hn::Set(di, int(view.col)));
  st.k_s = hn::IfThenElseZero(hn::RebindMask(di, m),
                              hn::Add(hn::Mul(sj, hn::Set(di, int(view.row))), col_term));
  st.k3 = hn::Mul(st.k_s, hn::Set(di, 3));
  // f.ray_P + L.dv * (sign * o) * float(view.stride)
  const V3 ray = RayAt(px.ray_P, L.dv, hn::Mul(sign, st.o), hn::Set(d, float(view.stride)));
  VF plane = zero;  // dot(S, n_s), from the view's table where it has one
  if (view.surface)
    GatherSurface(d, view.surface, st.k_s, st.n_s, plane);
  else
    st.n_s = Gather3(d, view.normal, st.k3);
  const VF denom = DotRay(ray, st.n_s);
  const MF steep =
      hn::Gt(hn::Mul(denom, denom), hn::Mul(hn::Set(d, march::kGrazing2), DotRay(ray, ray)));
  if (view.surface) {
    // S itself only where the move does not apply.
    st.S = ScaleRay(ray, hn::Div(plane, denom));
    if (!hn::AllFalse(d, hn::AndNot(steep, m)))
      st.S = Select(steep, st.S, Gather3(d, view.position, st.k3));
  } else {
    const V3 S = Gather3(d, view.position, st.k3);
    st.S = Select(steep, ScaleRay(ray, hn::Div(Dot(S, st.n_s), denom)), S);
  }
  st.d3 = Sub3(st.S, px.P);
  st.dist2 = Dot(st.d3, st.d3);
  st.m = hn::And(m, hn::And(hn::Lt(st.dist2, hn::Set(d, px.rg2)), hn::Gt(st.dist2, zero)));
  return st;
}

// The lanes' sums into out[base + l], for the valid lanes of the run, in lane order;
// each(l) runs just before lane l is stored.
template <class Each>
HWY_INLINE void StoreSums(DF d, MF valid, int base, int count, VF ao, VF vis, const V3& bent,
                          const V3& irradiance, PixelSums* out, Each each) {
  HWY_ALIGN float o_ao[kMaxLanes], o_vis[kMaxLanes], o_b[3][kMaxLanes], o_e[3][kMaxLanes];
  HWY_ALIGN float valid_f[kMaxLanes];
  hn::Store(ao, d, o_ao);
  hn::Store(vis, d, o_vis);
  hn::Store(bent.x, d, o_b[0]);
  hn::Store(bent.y, d, o_b[1]);
  hn::Store(bent.z, d, o_b[2]);
  hn::Store(irradiance.x, d, o_e[0]);
  hn::Store(irradiance.y, d, o_e[1]);
  hn::Store(irradiance.z, d, o_e[2]);
  hn::Store(hn::IfThenElseZero(valid, hn::Set(d, 1.f)), d, valid_f);
  for (size_t l = 0; l < hn::Lanes(d) && base + int(l) < count; ++l) {
    if (valid_f[l] == 0.f) continue;
    each(l);
    PixelSums& r = out[base + l];
    r.ao = o_ao[l];
    r.vis = o_vis[l];
    r.bent = Vec3{o_b[0][l], o_b[1][l], o_b[2][l]};
    r.irradiance = Vec3{o_e[0][l], o_e[1][l], o_e[2][l]};
  }
}

}  // namespace simd
}  // namespace hbil::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // HBIL_MARCH_SIMD_INL_H_
