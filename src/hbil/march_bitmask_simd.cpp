// march_bitmask_simd.cpp: the bitmask march (march_bitmask.cpp) over a run of pixels of one
// row, one pixel per SIMD lane, with Google Highway's dynamic dispatch (the widest
// instruction set of the machine: 16 lanes with AVX-512, 8 with AVX2).
//
// Every lane does exactly the scalar reference's arithmetic, in the same order and without
// fused multiply-adds, so the results are the scalar ones to the bit
// (tests/march_test.cpp). What changes is the control flow:
//  - a lane's `continue` becomes a mask for that sample, its `break` (the screen edge) a
//    mask for the rest of the side;
//  - the sample's fields are gathered by index (position, normal, thickness, radiance);
//  - the sectors a sample newly covers weigh, run by run of consecutive sectors, lowest
//    first, the AO antiderivative at the run's end minus that at its start, both read by
//    index from a per-lane table of the 33 boundaries (a stack buffer, with the gather only);
//  - the open sectors' sums take the boundaries after the steps, one at a time, from the
//    gather's tables of them (ao, vis and the bent vector's two terms) or, without the
//    gather, computed there;
//  - with a GatherLog, each lane's lit samples are kept per lane and appended pixel by pixel
//    after the vector, in the scalar march's order.
// Lanes of background pixels and past the run's end are masked off from the start.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "hbil/march_bitmask_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
//
#include <hwy/highway.h>

#include <bit>
#include <cstdint>

#include "hbil/march_simd-inl.h"

HWY_BEFORE_NAMESPACE();
namespace hbil::HWY_NAMESPACE {

namespace {

using namespace simd;

// The index of the one set bit of each lane of `bit` (a power of two, as the unsigned
// integer it is), from the exponent of its conversion to float (exact); bit 31 converts as
// −2³¹, whose exponent is the same.
HWY_INLINE VI BitIndex(DF d, VU bit) {
  const DI di;
  const DU du;
  const VU bits = hn::BitCast(du, hn::ConvertTo(d, hn::BitCast(di, bit)));
  return hn::Sub(hn::BitCast(di, hn::And(hn::ShiftRight<23>(bits), hn::Set(du, 0xFFu))),
                 hn::Set(di, 127));
}

// int(std::floor(v + 0.5f)) clamped to [0, kSectors] (a NaN becomes 0), through WholeToInt.
HWY_INLINE VI SectorIndex(DF d, VF v) {
  const VF f = hn::Floor(hn::Add(v, hn::Set(d, 0.5f)));
  return WholeToInt(d, hn::Min(hn::Max(f, hn::Zero(d)), hn::Set(d, float(march::kSectors))));
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
  const float cd = std::cos(kSectorWidth), sd = std::sin(kSectorWidth);
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.f), half = hn::Set(d, 0.5f);
  const VF stride = hn::Set(d, float(view.stride));
  const VF grazing2 = hn::Set(d, kGrazing2);
  const MF none = hn::FirstN(d, 0);
  const VI lane_iota = hn::Iota(di, 0), lanes_n = hn::Set(di, int(N));
  const bool has_fill = gather && view.fills(c);
  const V3 fill_c{hn::Set(d, c.fill.x), hn::Set(d, c.fill.y), hn::Set(d, c.fill.z)};

  // Per-lane scratch for the gather: the boundaries' antiderivatives (33 per lane), AO for
  // the sector weights, all four again for the open sectors' sums.
  HWY_ALIGN float b_ao[(kSectors + 1) * kMaxLanes], b_vis[(kSectors + 1) * kMaxLanes],
      b_bx[(kSectors + 1) * kMaxLanes], b_by[(kSectors + 1) * kMaxLanes];

  if (!view.radiance) log = nullptr;
  // The gather log, lane by lane until the lanes' pixels are appended in order: lane l's
  // entries are lane_entries[l * cap, l * cap + lane_n[l]), its count of slice s
  // lane_counts[l * n_slices + s]. A lane logs at most one entry a step and side and one
  // fill a slice, so each lane's run has room for them all (no growth, no check per entry);
  // only the lanes that log are visited, through the bits of their mask.
  std::vector<GatherEntry> lane_entries;
  std::vector<std::uint16_t> lane_counts(log ? N * size_t(n_slices) : 0);
  size_t cap = 0;
  std::uint32_t lane_n[kMaxLanes] = {}, slice_start[kMaxLanes] = {};
  auto begin_slice = [&] {
    for (size_t l = 0; l < N; ++l) slice_start[l] = lane_n[l];
  };
  auto end_slice = [&](int s) {
    for (size_t l = 0; l < N; ++l)
      lane_counts[l * n_slices + s] = std::uint16_t(lane_n[l] - slice_start[l]);
  };
  // Appends {src, fw, w} to every lane of `logs`.
  auto log_lanes = [&](const std::uint32_t* src, const float* fw, const float* w, MF logs) {
    std::uint8_t bits[(kMaxLanes + 7) / 8 + 8] = {};
    hn::StoreMaskBits(d, logs, bits);
    GatherEntry* e = lane_entries.data();
    for (size_t byte = 0; 8 * byte < N; ++byte)
      for (unsigned b = bits[byte]; b != 0; b &= b - 1) {
        const size_t l = 8 * byte + size_t(std::countr_zero(b));
        e[l * cap + lane_n[l]++] = {src[l], fw[l], w[l]};
      }
  };
  for (int base = 0; base < count; base += int(N)) {
    const PixelLanes px = LoadPixels(d, view, i0, j, base, count, c);
    if (hn::AllFalse(d, px.valid)) continue;
    if (log) {
      cap = size_t(n_slices) * (2 * size_t(px.n_steps) + 1);
      if (lane_entries.size() < N * cap) lane_entries.resize(N * cap);
      for (size_t l = 0; l < N; ++l) lane_n[l] = 0;
    }
    const V3 &P = px.P, &wo = px.wo, &ray_P = px.ray_P;
    auto offset = [&](int q) { return StepOffset(d, px, c, fraction, q); };

    VF acc_ao = zero, acc_vis = zero;
    V3 acc_b{zero, zero, zero}, acc_e{zero, zero, zero};
    for (int s = 0; s < n_slices; ++s) {
      const SliceLanes L = SliceLine(d, px, c, phi[s]);
      const MF live = L.live;
      if (log) begin_slice();
      if (hn::AllFalse(d, live)) {
        if (log) end_slice(s);
        continue;
      }
      const V3& D = L.D;
      const VF &dx = L.dx, &dy = L.dy, &nx = L.nx, &ny = L.ny;
      // γ and the boundaries' antiderivatives (march_bitmask.cpp).
      const VF sector0 = hn::Sub(FastAtan2(d, nx, ny), hn::Set(d, 0.5f * kPi));
      const VF nl = hn::Sqrt(hn::Add(hn::Mul(nx, nx), hn::Mul(ny, ny)));
      const MF has_n = hn::Gt(nl, zero);
      const VF sb0 = hn::IfThenElse(has_n, hn::Div(hn::Neg(ny), nl), hn::Set(d, -1.f));
      const VF cb0 = hn::IfThenElse(has_n, hn::Div(nx, nl), zero);
      // fn(k, G(boundary k)) for k = 0 … kSectors, in order.
      auto for_each_boundary = [&](auto fn) {
        const VF vcd = hn::Set(d, cd), vsd = hn::Set(d, sd);
        VF sb = sb0, cb = cb0;
        for (int k = 0; k <= kSectors; ++k) {
          const VF t = hn::Add(sector0, hn::Set(d, float(k) * kSectorWidth));
          fn(k, AntiderivativeAt(d, t, sb, cb, nx, ny));
          const VF sn = hn::Add(hn::Mul(sb, vcd), hn::Mul(cb, vsd));
          cb = hn::Sub(hn::Mul(cb, vcd), hn::Mul(sb, vsd));
          sb = sn;
        }
      };
      // The gather's sector weights (fresh sectors, fill) need every boundary's ao before
      // the steps, and keep the boundaries for the march's own sums after them; without
      // the gather, the sums take the boundaries after the steps.
      if (gather) {
        for_each_boundary([&](int k, const Antiderivative& g) {
          hn::Store(g.ao, d, b_ao + k * N);
          hn::Store(g.vis, d, b_vis + k * N);
          hn::Store(g.bx, d, b_bx + k * N);
          hn::Store(g.by, d, b_by + k * N);
        });
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
        // sign · fast_acos(std::clamp(±√|q|, −1, 1)), taken on the magnitude: the clamp is
        // min(√|q|, 1), and the cosine is negative exactly where q is (the root of a positive
        // float is positive). A key is never NaN (the sample's own has |X − P|² > 0, and a
        // NaN key never wins a comparison), so the result is the scalar's to the bit.
        auto angle_of_key = [&](VF q) {
          const VF r = AcosOfMagnitude(d, hn::Min(hn::Sqrt(hn::Abs(q)), one));
          return hn::Mul(sign, hn::IfThenElse(hn::Lt(q, zero), hn::Sub(hn::Set(d, kPi), r), r));
        };
        auto ray_at = [&](VF o) {  // f.ray_P + L.dv * (sign * o) * float(view.stride)
          return RayAt(ray_P, L.dv, hn::Mul(sign, o), stride);
        };
        MF alive = live;  // not yet past the screen edge
        for (int k = 0; k < px.n_steps && !hn::AllFalse(d, alive); ++k) {
          const bool near = k < c.steps;
          const StepLanes st = TakeStep(d, view, j, k, sx, sy, sign, px, L, c, fraction, alive);
          MF m = st.m;
          if (hn::AllFalse(d, m)) continue;
          const VF o = st.o;
          const VI k_s = st.k_s;
          const V3 &S = st.S, &n_s = st.n_s, &d3 = st.d3;
          const VF dist2 = st.dist2;
          const MF in_ao = near ? hn::And(m, hn::Lt(dist2, hn::Set(d, px.r2))) : none;
          const VF c_f = Dot(d3, wo);
          const VF key_f = hn::Div(hn::Mul(c_f, hn::Abs(c_f)), dist2);
          MF measured = none;
          VF t = hn::Add(hn::Set(d, near ? c.thickness : c.gather_thickness),
                         hn::Mul(hn::Set(d, c.thickness_growth), S.z));
          if (view.thickness) {
            const VF th = hn::GatherIndex(d, view.thickness, k_s);
            measured = hn::And(m, hn::Ge(th, zero));
            t = hn::IfThenElse(measured, th, t);
          }
          VF key_hi = key_f, key_lo = key_f;
          // key_hi < q ? q : key_hi is Max(q, key_hi) and q < key_lo ? q : key_lo is
          // Min(q, key_lo): x86's give the second operand where neither is larger, and
          // where another target gives the first, it differs only in a zero's sign, which
          // the angle ignores (keys are never NaN).
          auto cover_all = [&](VF q) {
            key_hi = hn::Max(q, key_hi);
            key_lo = hn::Min(q, key_lo);
          };
          auto cover = [&](VF q, MF where) {
            key_hi = hn::IfThenElse(where, hn::Max(q, key_hi), key_hi);
            key_lo = hn::IfThenElse(where, hn::Min(q, key_lo), key_lo);
          };
          cover_all(key(Add3(S, Scale(S, hn::Div(t, hn::Sqrt(Dot(S, S)))))));
          if (!hn::AllFalse(d, measured)) {
            const VF o_prev = k == 0 ? zero : hn::Min(offset(k - 1), o);
            const VF lo_o = hn::Mul(half, hn::Add(o, o_prev));
            const bool last = k + 1 == (near ? c.steps : px.n_steps);
            const VF hi_o = last ? hn::Add(o, hn::Mul(half, hn::Sub(o, o_prev)))
                                 : hn::Mul(half, hn::Add(o, hn::Max(offset(k + 1), o)));
            const VF plane = Dot(S, n_s);
            for (const VF& oo : {lo_o, hi_o}) {
              const V3 r = ray_at(oo);
              const VF den = DotRay(r, n_s);
              MF ok = hn::And(measured, hn::Gt(hn::Mul(den, den), hn::Mul(grazing2, DotRay(r, r))));
              const V3 X = ScaleRay(r, hn::Div(plane, den));
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
          // The fresh sectors' AO weight, run by run in every lane (march_bitmask.cpp), the
          // runs' ends read from the boundary table by index; most lanes have one run.
          VF w = zero;
          for (VU f = fresh;;) {
            const MF active = hn::RebindMask(d, hn::Ne(f, hn::Zero(du)));
            if (hn::AllFalse(d, active)) break;
            const VU low = hn::And(f, hn::Sub(hn::Zero(du), f)), g = hn::Add(f, low);
            const VU end_bit = hn::AndNot(f, g);
            const VI s_at = hn::Add(hn::Mul(BitIndex(d, low), lanes_n), lane_iota);
            const VI e_at =
                hn::Add(hn::Mul(hn::IfThenElse(hn::RebindMask(di, hn::Eq(end_bit, hn::Zero(du))),
                                               hn::Set(di, kSectors), BitIndex(d, end_bit)),
                                lanes_n),
                        lane_iota);
            const auto act = hn::RebindMask(di, active);
            const VF bs = hn::GatherIndex(d, b_ao, hn::IfThenElseZero(act, s_at));
            const VF be = hn::GatherIndex(d, b_ao, hn::IfThenElseZero(act, e_at));
            w = hn::IfThenElse(active, hn::Add(w, hn::Sub(be, bs)), w);
            f = hn::And(f, g);
          }
          // view.radiance[k_s] * facing_weight(n_s·d3 / dist) * w
          const VF fw = FacingWeight(d, Dot(n_s, d3), hn::Sqrt(dist2));
          const V3 L = Gather3(d, view.radiance, st.k3);
          const V3 add = Scale(Scale(L, fw), w);
          irradiance = Select(any_fresh, Add3(irradiance, add), irradiance);
          if (log) {
            HWY_ALIGN std::uint32_t k_lane[kMaxLanes];
            HWY_ALIGN float fw_lane[kMaxLanes], w_lane[kMaxLanes];
            hn::Store(hn::BitCast(du, k_s), du, k_lane);
            hn::Store(fw, d, fw_lane);
            hn::Store(w, d, w_lane);
            log_lanes(k_lane, fw_lane, w_lane, any_fresh);
          }
        }
      }
      // The directions the gather found empty see c.fill (march_bitmask.cpp).
      if (has_fill) {
        VF w = zero;
        for (int k = 0; k < kSectors; ++k) {
          const MF open_g =
              hn::RebindMask(d, hn::Eq(hn::And(occluded_g, hn::Set(du, 1u << k)), hn::Zero(du)));
          const VF wk = hn::Sub(hn::Load(d, b_ao + (k + 1) * N), hn::Load(d, b_ao + k * N));
          w = hn::IfThenElse(open_g, hn::Add(w, wk), w);
        }
        const V3 fill = view.fill ? Gather3(d, view.fill, px.own3) : fill_c;
        irradiance = Add3(irradiance, Scale(fill, w));
        if (log) {
          HWY_ALIGN std::uint32_t src_lane[kMaxLanes];
          HWY_ALIGN float fw_lane[kMaxLanes], w_lane[kMaxLanes];
          hn::Store(hn::Set(du, GatherEntry::kFillSource), du, src_lane);
          hn::Store(one, d, fw_lane);
          hn::Store(w, d, w_lane);
          log_lanes(src_lane, fw_lane, w_lane, live);
        }
      }
      // The open sectors' sums, boundary by boundary (march_bitmask.cpp).
      VF s_ao = zero, s_vis = zero, s_bx = zero, s_by = zero;
      MF before = none;  // sector k − 1 is open
      auto add_boundary = [&](int k, const Antiderivative& g) {
        const MF after =
            k < kSectors ? hn::RebindMask(d, hn::Eq(hn::And(occluded, hn::Set(du, 1u << (k & 31))),
                                                    hn::Zero(du)))
                         : none;
        const VF coef = hn::Sub(hn::IfThenElseZero(before, one), hn::IfThenElseZero(after, one));
        s_ao = hn::Add(s_ao, hn::Mul(coef, g.ao));
        s_vis = hn::Add(s_vis, hn::Mul(coef, g.vis));
        s_bx = hn::Add(s_bx, hn::Mul(coef, g.bx));
        s_by = hn::Add(s_by, hn::Mul(coef, g.by));
        before = after;
      };
      if (gather) {
        for (int k = 0; k <= kSectors; ++k)
          add_boundary(k, {hn::Load(d, b_ao + k * N), hn::Load(d, b_vis + k * N),
                           hn::Load(d, b_bx + k * N), hn::Load(d, b_by + k * N)});
      } else {
        for_each_boundary(add_boundary);
      }
      acc_ao = hn::IfThenElse(live, hn::Add(acc_ao, s_ao), acc_ao);
      acc_vis = hn::IfThenElse(live, hn::Add(acc_vis, s_vis), acc_vis);
      acc_b = Select(live, Add3(acc_b, Add3(Scale(D, s_bx), Scale(wo, s_by))), acc_b);
      acc_e = Select(live, Add3(acc_e, irradiance), acc_e);
      if (log) end_slice(s);
    }
    StoreSums(d, px.valid, base, count, acc_ao, acc_vis, acc_b, acc_e, out, [&](size_t l) {
      if (!log) return;
      const GatherEntry* e = lane_entries.data() + l * cap;
      log->entries.insert(log->entries.end(), e, e + lane_n[l]);
      const std::uint16_t* n = lane_counts.data() + l * n_slices;
      log->counts.insert(log->counts.end(), n, n + n_slices);
    });
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
  auto scalar = [&](int i, const Vec3& P, const Vec3& n) {
    return march_bitmask_pixel(view, i, j, P, n, phi, n_slices, fraction, c, log);
  };
  if (march::march_row_scalar_if_too_large(view, i0, j, count, out, scalar)) return;
  HWY_DYNAMIC_DISPATCH(MarchBitmaskRow)(view, i0, j, count, phi, n_slices, fraction, c, out, log);
}
}  // namespace hbil
#endif
