// march_horizon.cpp: the two-horizon march of one pixel (HBIL §1.3, §2.1, §2.2, eq. 16-18).
// See horizon.h for the departures from the paper.
#include <algorithm>
#include <cmath>

#include "hbil/march.h"
#include "hbil/march_common.h"

namespace hbil {

using namespace march;

PixelSums march_horizon_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                              const float* phi, int n_slices, const float* fraction,
                              const HorizonConfig& c) {
  PixelSums acc;
  const MarchSetup m = march_setup(view, P, c);
  const PixelFrame& f = m.f;
  for (int s = 0; s < n_slices; ++s) {
    SliceLine L;
    if (!slice_line(f, n, std::cos(phi[s]), std::sin(phi[s]), c, L)) continue;
    const float gamma = std::atan2(L.nx, L.ny);  // angle of n' from ω_o
    // A horizon angle with its sine and cosine: a sample's angle comes from its cosine, so the
    // band it sweeps is weighted (eq. 18) without a sine or cosine per sample.
    struct Angle {
      float t, s, c;
    };
    auto G = [&](const Angle& a) { return antiderivative(a.t, a.s, a.c, L.nx, L.ny); };
    auto angle = [](float t) { return Angle{t, std::sin(t), std::cos(t)}; };
    // The current horizons, starting at the tangent plane (§2.1); those of the gather (g)
    // see the samples up to the gather radius.
    float theta1 = std::min(gamma + 0.5f * kPi, kPi), theta0 = std::max(gamma - 0.5f * kPi, -kPi);
    Angle h1_g = angle(theta1), h0_g = angle(theta0);
    Vec3 irradiance;
    for (int side = 0; side < 2; ++side) {
      const float sx = side == 0 ? L.dx : -L.dx, sy = side == 0 ? L.dy : -L.dy;
      const float sign = side == 0 ? 1.f : -1.f;  // θ > 0 on the +D side
      for (int k = 0; k < m.n_steps; ++k) {
        Step st;
        const StepResult r = take_step(view, i, j, k, sx, sy, sign, P, L, m, c, fraction, st);
        if (r == StepResult::edge) break;  // screen edge
        if (r == StepResult::skip) continue;
        const bool in_ao = k < c.steps && st.dist2 < m.r2;
        const float dist = std::sqrt(st.dist2);
        const float cos_f = std::clamp(dot(st.d3, f.wo) / dist, -1.f, 1.f);
        const float theta_f = sign * fast_acos(cos_f);  // as the bitmask march: within 7e-5 rad
        // A rise of the horizon occludes, and is lit by, the band it sweeps (eq. 18).
        if (in_ao) {
          if (side == 0)
            theta1 = std::min(theta1, theta_f);
          else
            theta0 = std::max(theta0, theta_f);
        }
        if (!m.gather) continue;
        Angle& h = side == 0 ? h1_g : h0_g;
        if (side == 0 ? !(theta_f < h.t) : !(theta_f > h.t)) continue;
        const Angle a{theta_f, sign * std::sqrt(std::max(0.f, 1.f - cos_f * cos_f)), cos_f};
        const float w = side == 0 ? G(h).ao - G(a).ao : G(a).ao - G(h).ao;
        h = a;
        irradiance +=
            view.radiance[st.k_s] * facing_weight(dot(view.normal[st.k_s], st.d3) / dist) * w;
      }
    }
    // The band between the gather's horizons, where it found nothing, sees `fill`.
    if (m.gather && view.fills(c)) {
      const float w = h0_g.t < h1_g.t ? G(h1_g).ao - G(h0_g).ao : 0.f;
      irradiance += view.fill_at(c, i, j) * w;
    }
    theta1 = std::max(theta1, theta0);
    const SliceTerms t = integrate_slice(theta0, theta1, L.nx, L.ny);
    acc.ao += t.ao;
    acc.vis += t.vis;
    acc.bent += L.D * t.bx + f.wo * t.by;
    acc.irradiance += irradiance;
  }
  return acc;
}

PixelSums march_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                      const float* phi, int n_slices, const float* fraction, const HorizonConfig& c,
                      GatherLog* log) {
  return c.bitmask ? march_bitmask_pixel(view, i, j, P, n, phi, n_slices, fraction, c, log)
                   : march_horizon_pixel(view, i, j, P, n, phi, n_slices, fraction, c);
}

}  // namespace hbil
