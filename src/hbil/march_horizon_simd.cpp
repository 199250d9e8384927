// march_horizon_simd.cpp: the two-horizon march (march_horizon.cpp) over a run of pixels of
// one row, one pixel per SIMD lane, with Google Highway's dynamic dispatch.
//
// Every lane does exactly the scalar reference's arithmetic, in the same order and without
// fused multiply-adds, so the results are the scalar ones to the bit (tests/march_test.cpp).
// Only what the scalar march takes once per slice from libm (γ = atan2(n'x, n'y), the sine
// and cosine of the starting horizons and of the final ones) is taken lane by lane from the
// same libm. A lane's `continue` becomes a mask for that sample, its `break` (the screen
// edge) a mask for the rest of the side.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "hbil/march_horizon_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/highway.h>

#include <cstdint>

#include "hbil/march_simd-inl.h"

HWY_BEFORE_NAMESPACE();
namespace hbil::HWY_NAMESPACE {
namespace {

using namespace simd;

}  // namespace

void MarchHorizonRow(const SampleView& view, int i0, int j, int count, const float* phi,
                     int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out) {
  using namespace march;
  const DF d;
  const size_t N = hn::Lanes(d);
  const bool gather = view.radiance != nullptr;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.f);
  const bool has_fill = gather && view.fills(c);
  const V3 fill_c{hn::Set(d, c.fill.x), hn::Set(d, c.fill.y), hn::Set(d, c.fill.z)};
  HWY_ALIGN float lane_a[kMaxLanes], lane_b[kMaxLanes], lane_c[kMaxLanes], lane_d[kMaxLanes];
  // Per lane: sin and cos of `t` from libm, as the scalar march takes them.
  auto sin_cos = [&](VF t, VF& s, VF& co) {
    hn::Store(t, d, lane_a);
    for (size_t l = 0; l < N; ++l) lane_b[l] = std::sin(lane_a[l]), lane_c[l] = std::cos(lane_a[l]);
    s = hn::Load(d, lane_b);
    co = hn::Load(d, lane_c);
  };
  for (int base = 0; base < count; base += int(N)) {
    const PixelLanes px = LoadPixels(d, view, i0, j, base, count, c);
    if (hn::AllFalse(d, px.valid)) continue;
    VF acc_ao = zero, acc_vis = zero;
    V3 acc_b{zero, zero, zero}, acc_e{zero, zero, zero};
    for (int s = 0; s < n_slices; ++s) {
      const SliceLanes L = SliceLine(d, px, c, phi[s]);
      if (hn::AllFalse(d, L.live)) continue;
      hn::Store(L.nx, d, lane_a);
      hn::Store(L.ny, d, lane_d);
      for (size_t l = 0; l < N; ++l) lane_a[l] = std::atan2(lane_a[l], lane_d[l]);
      const VF gamma = hn::Load(d, lane_a);
      const VF half_pi = hn::Set(d, 0.5f * kPi), pi = hn::Set(d, kPi);
      // std::min(γ + π/2, π), std::max(γ − π/2, −π)
      const VF up = hn::Add(gamma, half_pi), down = hn::Sub(gamma, half_pi);
      VF theta1 = hn::IfThenElse(hn::Lt(pi, up), pi, up);
      VF theta0 = hn::IfThenElse(hn::Lt(down, hn::Neg(pi)), hn::Neg(pi), down);
      // The gather's horizons, with their sines and cosines.
      VF h1_t = theta1, h0_t = theta0, h1_s, h1_c, h0_s, h0_c;
      if (gather) {
        sin_cos(theta1, h1_s, h1_c);
        sin_cos(theta0, h0_s, h0_c);
      }
      V3 irradiance{zero, zero, zero};
      for (int side = 0; side < 2; ++side) {
        const VF sign = hn::Set(d, side == 0 ? 1.f : -1.f);
        const VF sx = side == 0 ? L.dx : hn::Neg(L.dx), sy = side == 0 ? L.dy : hn::Neg(L.dy);
        MF alive = L.live;  // not yet past the screen edge
        for (int k = 0; k < px.n_steps && !hn::AllFalse(d, alive); ++k) {
          const StepLanes st = TakeStep(d, view, j, k, sx, sy, sign, px, L, c, fraction, alive);
          if (hn::AllFalse(d, st.m)) continue;
          const MF in_ao =
              k < c.steps ? hn::And(st.m, hn::Lt(st.dist2, hn::Set(d, px.r2))) : hn::FirstN(d, 0);
          const VF dist = hn::Sqrt(st.dist2);
          const VF cos_f = Clamp(hn::Div(Dot(st.d3, px.wo), dist), hn::Set(d, -1.f), one);
          const VF theta_f = hn::Mul(sign, FastAcos(d, cos_f));
          // A rise of the horizon occludes, and is lit by, the band it sweeps (eq. 18).
          if (side == 0)
            theta1 = hn::IfThenElse(hn::And(in_ao, hn::Lt(theta_f, theta1)), theta_f, theta1);
          else
            theta0 = hn::IfThenElse(hn::And(in_ao, hn::Lt(theta0, theta_f)), theta_f, theta0);
          if (!gather) continue;
          VF& h_t = side == 0 ? h1_t : h0_t;
          VF& h_s = side == 0 ? h1_s : h0_s;
          VF& h_c = side == 0 ? h1_c : h0_c;
          const MF rise = hn::And(st.m, side == 0 ? hn::Lt(theta_f, h_t) : hn::Gt(theta_f, h_t));
          if (hn::AllFalse(d, rise)) continue;
          // sign * sqrt(max(0, 1 − cos²))
          const VF s2 = hn::Sub(one, hn::Mul(cos_f, cos_f));
          const VF sin_f = hn::Mul(sign, hn::Sqrt(hn::IfThenElse(hn::Lt(zero, s2), s2, zero)));
          const VF g_h = AntiderivativeAt(d, h_t, h_s, h_c, L.nx, L.ny).ao;
          const VF g_f = AntiderivativeAt(d, theta_f, sin_f, cos_f, L.nx, L.ny).ao;
          const VF w = side == 0 ? hn::Sub(g_h, g_f) : hn::Sub(g_f, g_h);
          h_t = hn::IfThenElse(rise, theta_f, h_t);
          h_s = hn::IfThenElse(rise, sin_f, h_s);
          h_c = hn::IfThenElse(rise, cos_f, h_c);
          const VF fw = FacingWeight(d, Dot(st.n_s, st.d3), dist);
          const V3 Ls = Gather3(d, view.radiance, st.k3);
          irradiance = Select(rise, Add3(irradiance, Scale(Scale(Ls, fw), w)), irradiance);
        }
      }
      // The band between the gather's horizons sees c.fill (march_horizon.cpp).
      if (has_fill) {
        const VF g1 = AntiderivativeAt(d, h1_t, h1_s, h1_c, L.nx, L.ny).ao;
        const VF g0 = AntiderivativeAt(d, h0_t, h0_s, h0_c, L.nx, L.ny).ao;
        const VF w = hn::IfThenElseZero(hn::Lt(h0_t, h1_t), hn::Sub(g1, g0));
        const V3 fill = view.fill ? Gather3(d, view.fill, px.own3) : fill_c;
        irradiance = Add3(irradiance, Scale(fill, w));
      }
      // std::max(theta1, theta0); integrate_slice(theta0, theta1, nx, ny).
      theta1 = hn::IfThenElse(hn::Lt(theta1, theta0), theta0, theta1);
      VF s1, c1, s0, c0;
      sin_cos(theta1, s1, c1);
      sin_cos(theta0, s0, c0);
      const Antiderivative g1 = AntiderivativeAt(d, theta1, s1, c1, L.nx, L.ny);
      const Antiderivative g0 = AntiderivativeAt(d, theta0, s0, c0, L.nx, L.ny);
      const VF t_ao = hn::Sub(g1.ao, g0.ao), t_vis = hn::Sub(g1.vis, g0.vis);
      const VF t_bx = hn::Sub(g1.bx, g0.bx), t_by = hn::Sub(g1.by, g0.by);
      acc_ao = hn::IfThenElse(L.live, hn::Add(acc_ao, t_ao), acc_ao);
      acc_vis = hn::IfThenElse(L.live, hn::Add(acc_vis, t_vis), acc_vis);
      acc_b = Select(L.live, Add3(acc_b, Add3(Scale(L.D, t_bx), Scale(px.wo, t_by))), acc_b);
      acc_e = Select(L.live, Add3(acc_e, irradiance), acc_e);
    }
    StoreSums(d, px.valid, base, count, acc_ao, acc_vis, acc_b, acc_e, out, [](size_t) {});
  }
}

}  // namespace hbil::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hbil {
HWY_EXPORT(MarchHorizonRow);

void march_horizon_row(const SampleView& view, int i0, int j, int count, const float* phi,
                       int n_slices, const float* fraction, const HorizonConfig& c,
                       PixelSums* out) {
  auto scalar = [&](int i, const Vec3& P, const Vec3& n) {
    return march_horizon_pixel(view, i, j, P, n, phi, n_slices, fraction, c);
  };
  if (march::march_row_scalar_if_too_large(view, i0, j, count, out, scalar)) return;
  HWY_DYNAMIC_DISPATCH(MarchHorizonRow)(view, i0, j, count, phi, n_slices, fraction, c, out);
}
}  // namespace hbil
#endif
