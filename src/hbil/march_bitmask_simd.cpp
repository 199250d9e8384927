// march_bitmask_simd.cpp: the bitmask march (march_bitmask.cpp) over a run of pixels of one
// row, one pixel per SIMD lane, with Google Highway's dynamic dispatch (the widest
// instruction set of the machine: 16 lanes with AVX-512, 8 with AVX2).
//
// Every lane does exactly the scalar reference's arithmetic, in the same order and without
// fused multiply-adds, so the results are the scalar ones to the bit
// (tests/march_test.cpp); only the per-slice angle γ = atan2(n'x, n'y) is taken from the
// scalar libm, lane by lane. What changes is the control flow:
//  - a lane's `continue` becomes a mask for that sample, its `break` (the screen edge) a
//    mask for the rest of the side;
//  - the sample's fields are gathered by index (position, normal, thickness, radiance);
//  - the sectors a sample newly covers are summed lowest first, one bit per lane per pass,
//    until no lane has any left (each sector is new at most once per slice);
//  - the sector weights of the 33 boundaries are a per-lane table in a stack buffer;
//  - with a GatherLog, each lane's lit samples are kept per lane and appended pixel by pixel
//    after the vector, in the scalar march's order.
// Lanes of background pixels and past the run's end are masked off from the start.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "hbil/march_bitmask_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/highway.h>

#include <climits>
#include <cstdint>

#include "hbil/gbuffer.h"
#include "hbil/march.h"
#include "hbil/march_common.h"

HWY_BEFORE_NAMESPACE();
namespace hbil::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

namespace {

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
// march::fast_acos, lane by lane.
HWY_INLINE VF FastAcos(DF d, VF x) {
  const VF a = hn::Abs(x);
  VF p = hn::Sub(hn::Set(d, 0.0742610f), hn::Mul(hn::Set(d, 0.0187293f), a));
  p = hn::Add(hn::Set(d, -0.2121144f), hn::Mul(a, p));
  p = hn::Add(hn::Set(d, 1.5707288f), hn::Mul(a, p));
  const VF r = hn::Mul(hn::Sqrt(hn::Sub(hn::Set(d, 1.f), a)), p);
  return hn::IfThenElse(hn::Lt(x, hn::Zero(d)), hn::Sub(hn::Set(d, march::kPi), r), r);
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
// int(std::floor(v + 0.5f)) clamped to [0, kSectors].
HWY_INLINE VI SectorIndex(DF d, VF v) {
  const VF f = hn::Floor(hn::Add(v, hn::Set(d, 0.5f)));
  const VF c = hn::Min(hn::Max(f, hn::Zero(d)), hn::Set(d, float(march::kSectors)));
  return hn::ConvertTo(DI(), c);
}

}  // namespace

void MarchBitmaskRow(const SampleView& view, int i0, int j, int count, const float* phi,
                     int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out,
                     GatherLog* log) {
  using namespace march;
  const DF d;
  const DI di;
  const DU du;
  const size_t N = hn::Lanes(d);
  const bool gather = view.radiance != nullptr;
  const bool far = gather && c.gather_steps > 0;
  const float r2 = c.radius * c.radius;
  const float rg2 = far ? c.gather_radius * c.gather_radius : r2;
  const int n_steps = c.steps + (far ? c.gather_steps : 0);
  const float cd = std::cos(kSectorWidth), sd = std::sin(kSectorWidth);
  const float focal = 0.5f * (c.fx + c.fy);
  const float diagonal = std::hypot(float(view.width), float(view.height));
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.f), half = hn::Set(d, 0.5f);
  const VF stride = hn::Set(d, float(view.stride));
  const VF grazing2 = hn::Set(d, kGrazing2);
  const VI lane = hn::Iota(di, 0);
  const MF none = hn::FirstN(d, 0);

  // Per-lane scratch: the boundary antiderivatives (33 per lane) and the slice angles.
  HWY_ALIGN float b_ao[(kSectors + 1) * kMaxLanes];
  HWY_ALIGN float b_vis[(kSectors + 1) * kMaxLanes];
  HWY_ALIGN float b_bx[(kSectors + 1) * kMaxLanes];
  HWY_ALIGN float b_by[(kSectors + 1) * kMaxLanes];
  HWY_ALIGN float lane_x[kMaxLanes], lane_y[kMaxLanes];
  HWY_ALIGN float o_ao[kMaxLanes], o_vis[kMaxLanes], o_b[3][kMaxLanes], o_e[3][kMaxLanes];

  if (!view.radiance) log = nullptr;
  // The gather log, lane by lane until the lanes' pixels are appended in order.
  std::vector<GatherEntry> lane_entries[kMaxLanes];
  std::vector<std::uint16_t> lane_counts[kMaxLanes];
  size_t slice_start[kMaxLanes] = {};
  auto begin_slice = [&] {
    for (size_t l = 0; l < N; ++l) slice_start[l] = lane_entries[l].size();
  };
  auto end_slice = [&] {
    for (size_t l = 0; l < N; ++l)
      lane_counts[l].push_back(std::uint16_t(lane_entries[l].size() - slice_start[l]));
  };
  for (int base = 0; base < count; base += int(N)) {
    for (size_t l = 0; l < N; ++l) lane_entries[l].clear(), lane_counts[l].clear();
    // Lanes: texels i0 + base + lane of row j; those past the run read the run's first.
    const VI ii = hn::Add(hn::Set(di, i0 + base), lane);
    const MF in_run = hn::RebindMask(d, hn::Lt(lane, hn::Set(di, count - base)));
    const VI i_safe = hn::IfThenElse(hn::RebindMask(di, in_run), ii, hn::Set(di, i0));
    const VI own = hn::Add(hn::Mul(hn::Set(di, int(view.row)), hn::Set(di, j)),
                           hn::Mul(i_safe, hn::Set(di, int(view.col))));
    const VI own3 = hn::Mul(own, hn::Set(di, 3));
    const V3 P = Gather3(d, view.position, own3);
    const V3 n = Gather3(d, view.normal, own3);
    const MF valid = hn::And(in_run, hn::Lt(P.z, hn::Set(d, ViewGBuffer::kBackground)));
    if (hn::AllFalse(d, valid)) continue;

    // march::pixel_frame.
    const V3 wo = NormalizeOrZero(d, {hn::Neg(P.x), hn::Neg(P.y), hn::Neg(P.z)});
    const V3 ray_P = {hn::Div(P.x, P.z), hn::Div(P.y, P.z), hn::Div(P.z, P.z)};
    const VF pz_stride = hn::Mul(P.z, stride);
    const VF r_tex =
        hn::Min(hn::Div(hn::Set(d, c.radius * focal), pz_stride), hn::Set(d, diagonal));
    const VF rg_tex =
        far ? hn::Min(hn::Div(hn::Set(d, c.gather_radius * focal), pz_stride), hn::Set(d, diagonal))
            : r_tex;
    const V3 e1 =
        NormalizeOrZero(d, {hn::Sub(one, hn::Mul(wo.x, wo.x)), hn::Sub(zero, hn::Mul(wo.y, wo.x)),
                            hn::Sub(zero, hn::Mul(wo.z, wo.x))});
    const V3 e2 = {hn::Sub(hn::Mul(wo.y, e1.z), hn::Mul(wo.z, e1.y)),
                   hn::Sub(hn::Mul(wo.z, e1.x), hn::Mul(wo.x, e1.z)),
                   hn::Sub(hn::Mul(wo.x, e1.y), hn::Mul(wo.y, e1.x))};
    // step_offset's two groups, per lane.
    const VF near_span = hn::Sub(r_tex, one);
    const VF far_start = hn::Max(r_tex, one), far_span = hn::Sub(rg_tex, r_tex);
    auto offset = [&](int q) {
      const VF fq = hn::Set(d, fraction[q]);
      return q < c.steps ? hn::Add(one, hn::Mul(near_span, fq))
                         : hn::Add(far_start, hn::Mul(far_span, fq));
    };
    const MF tiny = hn::Lt(r_tex, one);  // the AO radius is under a texel

    VF acc_ao = zero, acc_vis = zero;
    V3 acc_b{zero, zero, zero}, acc_e{zero, zero, zero};
    for (int s = 0; s < n_slices; ++s) {
      // march::slice_line.
      const VF cphi = hn::Set(d, std::cos(phi[s])), sphi = hn::Set(d, std::sin(phi[s]));
      const V3 D = Add3(Scale(e1, cphi), Scale(e2, sphi));
      const VF gx = hn::Mul(hn::Set(d, c.fx), hn::Sub(D.x, hn::Mul(ray_P.x, D.z)));
      const VF gy = hn::Mul(hn::Set(d, c.fy), hn::Sub(D.y, hn::Mul(ray_P.y, D.z)));
      const VF gl = hn::Sqrt(hn::Add(hn::Mul(gx, gx), hn::Mul(gy, gy)));
      const MF live = hn::And(valid, hn::Gt(gl, zero));
      if (log) begin_slice();
      if (hn::AllFalse(d, live)) {
        if (log) end_slice();
        continue;
      }
      const VF dx = hn::Div(gx, gl), dy = hn::Div(gy, gl);
      const V3 dv{hn::Div(dx, hn::Set(d, c.fx)), hn::Div(dy, hn::Set(d, c.fy)), zero};
      const VF nx = Dot(n, D), ny = Dot(n, wo);
      // γ and the boundary table (march_bitmask.cpp), lane by lane for γ.
      hn::Store(nx, d, lane_x);
      hn::Store(ny, d, lane_y);
      for (size_t l = 0; l < N; ++l) lane_x[l] = std::atan2(lane_x[l], lane_y[l]);
      const VF sector0 = hn::Sub(hn::Load(d, lane_x), hn::Set(d, 0.5f * kPi));
      const VF nl = hn::Sqrt(hn::Add(hn::Mul(nx, nx), hn::Mul(ny, ny)));
      const MF has_n = hn::Gt(nl, zero);
      VF sb = hn::IfThenElse(has_n, hn::Div(hn::Neg(ny), nl), hn::Set(d, -1.f));
      VF cb = hn::IfThenElse(has_n, hn::Div(nx, nl), zero);
      const VF vcd = hn::Set(d, cd), vsd = hn::Set(d, sd);
      for (int k = 0; k <= kSectors; ++k) {
        const VF t = hn::Add(sector0, hn::Set(d, float(k) * kSectorWidth));
        const VF a = hn::IfThenElse(hn::Lt(t, zero), hn::Set(d, -1.f), one);
        const VF sin2 = hn::Mul(hn::Sub(t, hn::Mul(sb, cb)), half);
        const VF sincos = hn::Mul(hn::Mul(sb, sb), half);
        hn::Store(hn::Mul(a, hn::Add(hn::Mul(nx, sin2), hn::Mul(ny, sincos))), d, b_ao + k * N);
        hn::Store(hn::Mul(a, hn::Sub(one, cb)), d, b_vis + k * N);
        hn::Store(hn::Mul(a, sin2), d, b_bx + k * N);
        hn::Store(hn::Mul(a, sincos), d, b_by + k * N);
        const VF sn = hn::Add(hn::Mul(sb, vcd), hn::Mul(cb, vsd));
        cb = hn::Sub(hn::Mul(cb, vcd), hn::Mul(sb, vsd));
        sb = sn;
      }
      VU occluded = hn::Zero(du), occluded_g = hn::Zero(du);
      V3 irradiance{zero, zero, zero};
      for (int side = 0; side < 2; ++side) {
        const float sgn_side = side == 0 ? 1.f : -1.f;
        const VF sign = hn::Set(d, sgn_side);
        const VF sx = side == 0 ? dx : hn::Neg(dx), sy = side == 0 ? dy : hn::Neg(dy);
        // key(X) = c|c| / |X − P|², c = (X − P)·ω_o (march_bitmask.cpp).
        auto key = [&](const V3& X) {
          const V3 dd = Sub3(X, P);
          const VF cv = Dot(dd, wo);
          return hn::Div(hn::Mul(cv, hn::Abs(cv)), Dot(dd, dd));
        };
        auto angle_of_key = [&](VF q) {
          const VF r = hn::Sqrt(hn::Abs(q));
          const VF cv = hn::IfThenElse(hn::Lt(q, zero), hn::Neg(r), r);
          return hn::Mul(sign, FastAcos(d, Clamp(cv, hn::Set(d, -1.f), one)));
        };
        auto ray_at = [&](VF o) {  // f.ray_P + L.dv * (sign * o) * float(view.stride)
          return Add3(ray_P, Scale(Scale(dv, hn::Mul(sign, o)), stride));
        };
        MF alive = live;  // not yet past the screen edge
        for (int k = 0; k < n_steps && !hn::AllFalse(d, alive); ++k) {
          const bool near = k < c.steps;
          MF m = near ? hn::AndNot(tiny, alive) : alive;
          const VF o = offset(k);
          const VI oi = hn::ConvertTo(di, hn::Floor(hn::Add(hn::Mul(sx, o), half)));
          const VI oj = hn::ConvertTo(di, hn::Floor(hn::Add(hn::Mul(sy, o), half)));
          const MF at_p =
              hn::RebindMask(d, hn::And(hn::Eq(oi, hn::Zero(di)), hn::Eq(oj, hn::Zero(di))));
          m = hn::AndNot(at_p, m);
          const VI si = hn::Add(ii, oi), sj = hn::Add(hn::Set(di, j), oj);
          const auto off_i =
              hn::Or(hn::Lt(si, hn::Zero(di)), hn::Gt(si, hn::Set(di, view.width - 1)));
          const auto off_j =
              hn::Or(hn::Lt(sj, hn::Zero(di)), hn::Gt(sj, hn::Set(di, view.height - 1)));
          const MF off = hn::And(m, hn::RebindMask(d, hn::Or(off_i, off_j)));
          alive = hn::AndNot(off, alive);
          m = hn::AndNot(off, m);
          if (hn::AllFalse(d, m)) continue;
          const VI k_s = hn::IfThenElseZero(hn::RebindMask(di, m),
                                            hn::Add(hn::Mul(sj, hn::Set(di, int(view.row))),
                                                    hn::Mul(si, hn::Set(di, int(view.col)))));
          const VI k3 = hn::Mul(k_s, hn::Set(di, 3));
          V3 S = Gather3(d, view.position, k3);
          const V3 n_s = Gather3(d, view.normal, k3);
          const V3 ray = ray_at(o);
          const VF denom = Dot(ray, n_s);
          const MF steep = hn::Gt(hn::Mul(denom, denom), hn::Mul(grazing2, Dot(ray, ray)));
          S = Select(steep, Scale(ray, hn::Div(Dot(S, n_s), denom)), S);
          const V3 d3 = Sub3(S, P);
          const VF dist2 = Dot(d3, d3);
          m = hn::And(m, hn::And(hn::Lt(dist2, hn::Set(d, rg2)), hn::Gt(dist2, zero)));
          if (hn::AllFalse(d, m)) continue;
          const MF in_ao = near ? hn::And(m, hn::Lt(dist2, hn::Set(d, r2))) : none;
          const VF c_f = Dot(d3, wo);
          const VF key_f = hn::Div(hn::Mul(c_f, hn::Abs(c_f)), dist2);
          MF measured = none;
          VF t = hn::Add(hn::Set(d, c.thickness), hn::Mul(hn::Set(d, c.thickness_growth), S.z));
          if (view.thickness) {
            const VF th = hn::GatherIndex(d, view.thickness, k_s);
            measured = hn::And(m, hn::Ge(th, zero));
            t = hn::IfThenElse(measured, th, t);
          }
          VF key_hi = key_f, key_lo = key_f;
          auto cover = [&](VF q, MF where) {
            key_hi = hn::IfThenElse(hn::And(where, hn::Lt(key_hi, q)), q, key_hi);
            key_lo = hn::IfThenElse(hn::And(where, hn::Lt(q, key_lo)), q, key_lo);
          };
          const MF all_lanes = hn::FirstN(d, N);
          cover(key(Add3(S, Scale(S, hn::Div(t, hn::Sqrt(Dot(S, S)))))), all_lanes);
          if (!hn::AllFalse(d, measured)) {
            const VF o_prev = k == 0 ? zero : hn::Min(offset(k - 1), o);
            const VF lo_o = hn::Mul(half, hn::Add(o, o_prev));
            const bool last = k + 1 == (near ? c.steps : n_steps);
            const VF hi_o = last ? hn::Add(o, hn::Mul(half, hn::Sub(o, o_prev)))
                                 : hn::Mul(half, hn::Add(o, hn::Max(offset(k + 1), o)));
            const VF plane = Dot(S, n_s);
            for (const VF& oo : {lo_o, hi_o}) {
              const V3 r = ray_at(oo);
              const VF den = Dot(r, n_s);
              MF ok = hn::And(measured, hn::Gt(hn::Mul(den, den), hn::Mul(grazing2, Dot(r, r))));
              const V3 X = Scale(r, hn::Div(plane, den));
              ok = hn::And(ok, hn::Gt(X.z, zero));
              if (hn::AllFalse(d, ok)) continue;
              cover(key(X), ok);
              cover(key(Add3(X, Scale(X, hn::Div(t, hn::Sqrt(Dot(X, X)))))), ok);
            }
          }
          const VF th_lo = angle_of_key(side == 0 ? key_hi : key_lo);
          const VF th_hi = angle_of_key(side == 0 ? key_lo : key_hi);
          const VF inv_width = hn::Set(d, kInvSectorWidth);
          const VI a = SectorIndex(d, hn::Mul(hn::Sub(th_lo, sector0), inv_width));
          const VI b = SectorIndex(d, hn::Mul(hn::Sub(th_hi, sector0), inv_width));
          m = hn::And(m, hn::RebindMask(d, hn::Gt(b, a)));
          if (hn::AllFalse(d, m)) continue;
          const VI span = hn::Sub(b, a);
          const VU all = hn::Set(du, ~0u);
          const VU ones = hn::Sub(hn::Set(du, 1u) << hn::BitCast(du, span), hn::Set(du, 1u));
          const VU run =
              hn::IfThenElse(hn::RebindMask(du, hn::Eq(span, hn::Set(di, 32))), all, ones);
          const VU mask = hn::IfThenElseZero(hn::RebindMask(du, m), run << hn::BitCast(du, a));
          occluded = hn::Or(occluded, hn::IfThenElseZero(hn::RebindMask(du, in_ao), mask));
          if (!gather) continue;
          VU fresh = hn::AndNot(occluded_g, mask);
          occluded_g = hn::Or(occluded_g, mask);
          if (hn::AllFalse(du, hn::Ne(fresh, hn::Zero(du)))) continue;
          const MF any_fresh = hn::RebindMask(d, hn::Ne(fresh, hn::Zero(du)));
          VF w = zero;
          for (;;) {
            const auto has = hn::Ne(fresh, hn::Zero(du));
            if (hn::AllFalse(du, has)) break;
            // The lowest set bit's index q from the exponent of float(bit).
            const VU low = hn::And(fresh, hn::Sub(hn::Zero(du), fresh));
            const VF lowf = hn::ConvertTo(d, hn::BitCast(di, low));
            const VI q =
                hn::Sub(hn::And(hn::ShiftRight<23>(hn::BitCast(di, lowf)), hn::Set(di, 0xFF)),
                        hn::Set(di, 127));
            const VI at = hn::IfThenElseZero(hn::RebindMask(di, has),
                                             hn::Add(hn::Mul(q, hn::Set(di, int(N))), lane));
            const VF wq = hn::Sub(hn::GatherIndex(d, b_ao + N, at), hn::GatherIndex(d, b_ao, at));
            w = hn::Add(w, hn::IfThenElseZero(hn::RebindMask(d, has), wq));
            fresh = hn::And(fresh, hn::Sub(fresh, hn::Set(du, 1u)));
          }
          // view.radiance[k_s] * facing_weight(n_s·d3 / dist) * w
          const VF dist = hn::Sqrt(dist2);
          VF x = hn::Mul(hn::Sub(hn::Set(d, 0.1f), hn::Div(Dot(n_s, d3), dist)), hn::Set(d, 5.f));
          x = Clamp(x, zero, one);
          const VF fw =
              hn::Mul(hn::Mul(x, x), hn::Sub(hn::Set(d, 3.f), hn::Mul(hn::Set(d, 2.f), x)));
          const V3 L = Gather3(d, view.radiance, k3);
          const V3 add = Scale(Scale(L, fw), w);
          irradiance = Select(any_fresh, Add3(irradiance, add), irradiance);
          if (log) {
            HWY_ALIGN std::int32_t k_lane[kMaxLanes];
            HWY_ALIGN float fw_lane[kMaxLanes], w_lane[kMaxLanes], fresh_lane[kMaxLanes];
            hn::Store(k_s, di, k_lane);
            hn::Store(fw, d, fw_lane);
            hn::Store(w, d, w_lane);
            hn::Store(hn::IfThenElseZero(any_fresh, one), d, fresh_lane);
            for (size_t l = 0; l < N; ++l)
              if (fresh_lane[l] != 0.f)
                lane_entries[l].push_back({std::uint32_t(k_lane[l]), fw_lane[l], w_lane[l]});
          }
        }
      }
      // The unoccluded sectors, in order (march_bitmask.cpp).
      for (int k = 0; k < kSectors; ++k) {
        const MF open = hn::And(
            live, hn::RebindMask(d, hn::Eq(hn::And(occluded, hn::Set(du, 1u << k)), hn::Zero(du))));
        if (hn::AllFalse(d, open)) continue;
        auto diff = [&](const float* tab) {
          return hn::Sub(hn::Load(d, tab + (k + 1) * N), hn::Load(d, tab + k * N));
        };
        const VF dbx = diff(b_bx), dby = diff(b_by);
        acc_ao = hn::IfThenElse(open, hn::Add(acc_ao, diff(b_ao)), acc_ao);
        acc_vis = hn::IfThenElse(open, hn::Add(acc_vis, diff(b_vis)), acc_vis);
        acc_b = Select(open, Add3(acc_b, Add3(Scale(D, dbx), Scale(wo, dby))), acc_b);
      }
      acc_e = Select(live, Add3(acc_e, irradiance), acc_e);
      if (log) end_slice();
    }
    hn::Store(acc_ao, d, o_ao);
    hn::Store(acc_vis, d, o_vis);
    hn::Store(acc_b.x, d, o_b[0]);
    hn::Store(acc_b.y, d, o_b[1]);
    hn::Store(acc_b.z, d, o_b[2]);
    hn::Store(acc_e.x, d, o_e[0]);
    hn::Store(acc_e.y, d, o_e[1]);
    hn::Store(acc_e.z, d, o_e[2]);
    HWY_ALIGN float valid_f[kMaxLanes];
    hn::Store(hn::IfThenElseZero(valid, one), d, valid_f);
    for (size_t l = 0; l < N && base + int(l) < count; ++l) {
      if (valid_f[l] == 0.f) continue;
      if (log) {
        log->entries.insert(log->entries.end(), lane_entries[l].begin(), lane_entries[l].end());
        log->counts.insert(log->counts.end(), lane_counts[l].begin(), lane_counts[l].end());
      }
      PixelSums& r = out[base + l];
      r.ao = o_ao[l];
      r.vis = o_vis[l];
      r.bent = Vec3{o_b[0][l], o_b[1][l], o_b[2][l]};
      r.irradiance = Vec3{o_e[0][l], o_e[1][l], o_e[2][l]};
    }
  }
}

}  // namespace hbil::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hbil {
HWY_EXPORT(MarchBitmaskRow);

const char* march_simd_target() {
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  return targets.empty() ? "none" : hwy::TargetName(targets.front());
}
void march_bitmask_row(const SampleView& view, int i0, int j, int count, const float* phi,
                       int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out,
                       GatherLog* log) {
  // The lanes index the view's floats with 32-bit integers: a view too large for them (more
  // than about 700 million texels) is marched by the scalar reference instead.
  const std::int64_t last =
      std::int64_t(view.height - 1) * view.row + std::int64_t(view.width - 1) * view.col;
  if (3 * last + 2 > std::int64_t(INT32_MAX)) {
    for (int k = 0; k < count; ++k) {
      const std::ptrdiff_t at = view.index(i0 + k, j);
      if (!(view.position[at].z < ViewGBuffer::kBackground)) continue;
      out[k] = march_bitmask_pixel(view, i0 + k, j, view.position[at], view.normal[at], phi,
                                   n_slices, fraction, c, log);
    }
    return;
  }
  HWY_DYNAMIC_DISPATCH(MarchBitmaskRow)(view, i0, j, count, phi, n_slices, fraction, c, out, log);
}
}  // namespace hbil
#endif
