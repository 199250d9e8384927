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
    auto G = [&](float t) { return antiderivative(t, std::sin(t), std::cos(t), L.nx, L.ny); };
    // The current horizons, starting at the tangent plane (§2.1); those of the gather (g)
    // see the samples up to the gather radius.
    float theta1 = std::min(gamma + 0.5f * kPi, kPi), theta0 = std::max(gamma - 0.5f * kPi, -kPi);
    float theta1_g = theta1, theta0_g = theta0;
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
        const float theta_f = sign * std::acos(std::clamp(dot(st.d3, f.wo) / dist, -1.f, 1.f));
        // A rise of the horizon occludes, and is lit by, the band it sweeps (eq. 18).
        auto rise = [&](float& t0, float& t1, float& lo, float& hi) {
          if (side == 0) {
            if (!(theta_f < t1)) return false;
            lo = theta_f, hi = t1, t1 = theta_f;
          } else {
            if (!(theta_f > t0)) return false;
            lo = t0, hi = theta_f, t0 = theta_f;
          }
          return true;
        };
        float lo, hi;
        if (in_ao) rise(theta0, theta1, lo, hi);
        if (m.gather && rise(theta0_g, theta1_g, lo, hi))
          irradiance += view.radiance[st.k_s] *
                        facing_weight(dot(view.normal[st.k_s], st.d3) / dist) *
                        (G(hi).ao - G(lo).ao);
      }
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
