// march_bitmask.cpp: the visibility-bitmask march of one pixel (Therrien et al. 2023,
// Algorithm 1, with HBIL's slices, eq. 16-18 gather and measured thickness); the scalar
// reference of march_bitmask_simd.cpp. See horizon.h for the departures from the papers.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "hbil/march.h"
#include "hbil/march_common.h"

namespace hbil {

using namespace march;

PixelSums march_bitmask_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                              const float* phi, int n_slices, const float* fraction,
                              const HorizonConfig& c, GatherLog* log) {
  PixelSums acc;
  if (!view.radiance) log = nullptr;
  const MarchSetup m = march_setup(view, P, c);
  const PixelFrame& f = m.f;
  const float cd = std::cos(kSectorWidth), sd = std::sin(kSectorWidth);
  for (int s = 0; s < n_slices; ++s) {
    SliceLine L;
    if (!slice_line(f, n, std::cos(phi[s]), std::sin(phi[s]), c, L)) {
      if (log) log->counts.push_back(0);
      continue;
    }
    const float gamma = fast_atan2(L.nx, L.ny);  // angle of n' from ω_o
    // 32 sectors over [γ − π/2, γ + π/2]; sector k's cosine-weighted integral is
    // W[k] = G(b_k) − G(a_k), so AO keeps the definition of eq. 9.
    const float sector0 = gamma - 0.5f * kPi;
    // Boundaries by rotation from (sin, cos)(γ − π/2) = (−n'_y, n'_x) / |n'|, without 33
    // sin/cos pairs.
    const float nl = std::sqrt(L.nx * L.nx + L.ny * L.ny);
    float sb = nl > 0.f ? -L.ny / nl : -1.f, cb = nl > 0.f ? L.nx / nl : 0.f;
    Antiderivative bound[kSectors + 1];
    for (int k = 0; k <= kSectors; ++k) {
      bound[k] = antiderivative(sector0 + float(k) * kSectorWidth, sb, cb, L.nx, L.ny);
      const float sn = sb * cd + cb * sd;
      cb = cb * cd - sb * sd;
      sb = sn;
    }
    std::uint32_t occluded = 0, occluded_g = 0;
    const size_t logged = log ? log->entries.size() : 0;
    Vec3 irradiance;
    for (int side = 0; side < 2; ++side) {
      const float sx = side == 0 ? L.dx : -L.dx, sy = side == 0 ? L.dy : -L.dy;
      const float sign = side == 0 ? 1.f : -1.f;  // θ > 0 on the +D side
      // Occluder extents are compared by a key of the direction from P to X that is monotone
      // in cos ∠(ω_o, X − P), cos |cos| = c|c| / |X − P|² (no square root), and only the
      // two extremes become angles: θ = sign · acos(cos), so on the + side the largest cos
      // is the lowest θ, on the − side the highest.
      auto key = [&](const Vec3& X) {
        const Vec3 d = X - P;
        const float c = dot(d, f.wo);
        return c * std::fabs(c) / dot(d, d);
      };
      auto angle_of_key = [&](float q) {
        const float c = q < 0.f ? -std::sqrt(-q) : std::sqrt(q);
        return sign * fast_acos(std::clamp(c, -1.f, 1.f));
      };
      for (int k = 0; k < m.n_steps; ++k) {
        Step st;
        const StepResult r = take_step(view, i, j, k, sx, sy, sign, P, L, m, c, fraction, st);
        if (r == StepResult::edge) break;  // screen edge
        if (r == StepResult::skip) continue;
        const bool near = k < c.steps;
        const bool in_ao = near && st.dist2 < m.r2;
        const float o = st.o;
        const Vec3& S = st.S;
        const Vec3& n_s = view.normal[st.k_s];
        const float c_f = dot(st.d3, f.wo);
        const float key_f = c_f * std::fabs(c_f) / st.dist2;
        // Algorithm 1: the sample is an occluder of thickness t along its view ray; it covers
        // [θf, θb] and lights the sectors it newly covers. Thickness: measured (back faces)
        // where known, else the constant heuristic.
        const bool measured = view.thickness && view.thickness[st.k_s] >= 0.f;
        const float t = measured
                            ? view.thickness[st.k_s]
                            : (near ? c.thickness : c.gather_thickness) + c.thickness_growth * S.z;
        float key_hi = key_f, key_lo = key_f;  // the largest and smallest key covered
        auto cover = [&](float q) {
          key_hi = key_hi < q ? q : key_hi;
          key_lo = q < key_lo ? q : key_lo;
        };
        cover(key(S + S * (t / length(S))));
        if (measured) {
          // A measured thickness is the object's own, so the sample must also stand for the
          // surface between it and its neighbours, which a point misses (light would leak
          // between samples on a wall): it covers its tangent plane between the rays through
          // the midpoints to its neighbours on the line, extruded by t along them. (The
          // constant thickness is a heuristic tuned with point samples; see horizon.h.)
          // The first sample reaches back only half way to P: nearer, the direction from P to
          // a point of another sample's plane is dominated by sub-pixel error (Blender's depth
          // is one jittered sample, P is placed at the pixel centre), so within about one
          // texel of a crease the surface between P and its first sample is missed.
          const float o_prev =
              k == 0 ? 0.f : std::min(step_offset(k - 1, c.steps, f.r_tex, f.rg_tex, fraction), o);
          const float lo_o = 0.5f * (o + o_prev);
          // Neighbours within the same group only: the last sample of a group reaches as far
          // beyond itself as its predecessor is before it, never towards the gather-only
          // samples, so ao is the same with or without them.
          const bool last = k + 1 == (near ? c.steps : m.n_steps);
          const float hi_o =
              last ? o + 0.5f * (o - o_prev)
                   : 0.5f * (o +
                             std::max(step_offset(k + 1, c.steps, f.r_tex, f.rg_tex, fraction), o));
          const float plane = dot(S, n_s);
          for (float oo : {lo_o, hi_o}) {
            const Vec3 r = f.ray_P + L.dv * (sign * oo) * float(view.stride);
            const float den = dot(r, n_s);
            if (!(den * den > kGrazing2 * dot(r, r))) continue;
            const Vec3 X = r * (plane / den);
            if (!(X.z > 0.f)) continue;
            cover(key(X));
            cover(key(X + X * (t / length(X))));
          }
        }
        const float th_lo = angle_of_key(side == 0 ? key_hi : key_lo);
        const float th_hi = angle_of_key(side == 0 ? key_lo : key_hi);
        const float lo = (th_lo - sector0) * kInvSectorWidth;
        const float hi = (th_hi - sector0) * kInvSectorWidth;
        // "Round" criterion: a sector counts when at least half covered.
        const int a = std::clamp(int(std::floor(lo + 0.5f)), 0, kSectors);
        const int b = std::clamp(int(std::floor(hi + 0.5f)), 0, kSectors);
        if (b <= a) continue;
        const std::uint32_t mask = (b - a == 32 ? ~0u : ((1u << (b - a)) - 1u)) << a;
        if (in_ao) occluded |= mask;
        if (!m.gather) continue;
        std::uint32_t fresh = mask & ~occluded_g;
        occluded_g |= mask;
        if (fresh) {
          // The fresh sectors' AO weight, run by run, lowest first: a run [s, e) weighs
          // G(e) − G(s). f + low clears the lowest run and sets the bit at its end (none
          // where the run ends at the last sector).
          float w = 0.f;
          for (std::uint32_t f = fresh; f != 0;) {
            const std::uint32_t low = f & (0u - f), g = f + low, end_bit = g & ~f;
            const int s = std::countr_zero(low);
            const int e = end_bit != 0 ? std::countr_zero(end_bit) : kSectors;
            w += bound[e].ao - bound[s].ao;
            f &= g;
          }
          const float fw = facing_weight(dot(n_s, st.d3) / std::sqrt(st.dist2));
          irradiance += view.radiance[st.k_s] * fw * w;
          if (log) log->entries.push_back({std::uint32_t(st.k_s), fw, w});
        }
      }
    }
    // The directions the gather found empty see `fill` (logged as one entry, last).
    if (m.gather && view.fills(c)) {
      float w = 0.f;
      for (int k = 0; k < kSectors; ++k)
        if (!(occluded_g >> k & 1u)) w += bound[k + 1].ao - bound[k].ao;
      irradiance += view.fill_at(c, i, j) * w;
      if (log) log->entries.push_back({GatherEntry::kFillSource, 1.f, w});
    }
    // The open sectors' sums: sector k spans boundaries k and k + 1, so Σ over the open k of
    // G(k + 1) − G(k) is Σ over the boundaries of (open(k − 1) − open(k)) G(k), with
    // open(−1) = open(32) = 0: each boundary once, in order (the vector march need not
    // keep a table of them for this).
    float s_ao = 0.f, s_vis = 0.f, s_bx = 0.f, s_by = 0.f;
    for (int k = 0; k <= kSectors; ++k) {
      const float before = k > 0 && !(occluded >> (k - 1) & 1u) ? 1.f : 0.f;
      const float after = k < kSectors && !(occluded >> k & 1u) ? 1.f : 0.f;
      const float coef = before - after;
      s_ao += coef * bound[k].ao;
      s_vis += coef * bound[k].vis;
      s_bx += coef * bound[k].bx;
      s_by += coef * bound[k].by;
    }
    acc.ao += s_ao;
    acc.vis += s_vis;
    acc.bent += L.D * s_bx + f.wo * s_by;
    acc.irradiance += irradiance;
    if (log) log->counts.push_back(std::uint16_t(log->entries.size() - logged));
  }
  return acc;
}

Vec3 replay_gather(const GatherLog& log, const Vec3* radiance, const Vec3& fill, int n_slices,
                   size_t& entry, size_t& count) {
  Vec3 acc;
  for (int s = 0; s < n_slices; ++s) {
    Vec3 irradiance;
    for (int k = log.counts[count++]; k > 0; --k) {
      const GatherEntry& e = log.entries[entry++];
      irradiance += e.src == GatherEntry::kFillSource ? fill * e.w : radiance[e.src] * e.fw * e.w;
    }
    acc += irradiance;
  }
  return acc;
}

}  // namespace hbil
