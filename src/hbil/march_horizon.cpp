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
  const bool gather = view.radiance != nullptr;
  // The gather may reach beyond the AO radius: gather_steps more samples per side between
  // the two radii, which only the gather sees (AO is the same with or without them).
  const bool far = gather && c.gather_steps > 0;
  const PixelFrame f = pixel_frame(view, P, c, far);
  const float r2 = c.radius * c.radius;
  const float rg2 = far ? c.gather_radius * c.gather_radius : r2;
  const int n_steps = c.steps + (far ? c.gather_steps : 0);
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
      for (int k = 0; k < n_steps; ++k) {
        const bool near = k < c.steps;
        if (near && f.r_tex < 1.f) continue;  // the AO radius is under a texel
        const float o = step_offset(k, c.steps, f.r_tex, f.rg_tex, fraction);
        const int oi = int(std::floor(sx * o + 0.5f)), oj = int(std::floor(sy * o + 0.5f));
        if (oi == 0 && oj == 0) continue;
        const int si = i + oi, sj = j + oj;
        if (si < 0 || sj < 0 || si >= view.width || sj >= view.height) break;  // screen edge
        const std::ptrdiff_t k_s = view.index(si, sj);
        Vec3 S = view.position[k_s];
        // Move S along its tangent plane onto the ray through the exact point of the line
        // (see horizon.h): that ray lies in the slice plane.
        const Vec3 ray = f.ray_P + L.dv * (sign * o) * float(view.stride);
        const Vec3& n_s = view.normal[k_s];
        const float denom = dot(ray, n_s);
        if (std::fabs(denom) > kGrazing * length(ray)) S = ray * (dot(S, n_s) / denom);
        const Vec3 d3 = S - P;  // background has z = 3e38, n = 0: |d3| > radius
        const float dist2 = dot(d3, d3);
        if (!(dist2 < rg2) || dist2 <= 0.f) continue;
        const bool in_ao = near && dist2 < r2;
        const float dist = std::sqrt(dist2);
        const float theta_f = sign * std::acos(std::clamp(dot(d3, f.wo) / dist, -1.f, 1.f));
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
        if (gather && rise(theta0_g, theta1_g, lo, hi))
          irradiance += view.radiance[k_s] * facing_weight(n_s, d3 / dist) * (G(hi).ao - G(lo).ao);
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
                      const float* phi, int n_slices, const float* fraction,
                      const HorizonConfig& c) {
  return c.bitmask ? march_bitmask_pixel(view, i, j, P, n, phi, n_slices, fraction, c)
                   : march_horizon_pixel(view, i, j, P, n, phi, n_slices, fraction, c);
}

}  // namespace hbil
