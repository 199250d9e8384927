// multibounce.cpp: see multibounce.h.
#include "hbil/multibounce.h"

#include <algorithm>
#include <cmath>

namespace hbil {

double multibounce_F0(double alpha) {
  alpha = std::clamp(alpha, 0.0, 1.0);
  return alpha * (1.0 + 0.5 * std::pow(1.0 - alpha, 0.75));  // eq. 7
}

double multibounce_F1(double alpha) {
  alpha = std::clamp(alpha, 0.0, 1.0);
  return kMultibounceA * alpha * std::pow(1.0 - alpha, 1.5) *
         std::exp(-kMultibounceB * std::sqrt(std::sqrt(alpha)));  // eq. 11
}

double multibounce_alpha_max() {
  // F0 is concave on [0, 1) and crosses 1 once below its maximum at α ≈ 0.983.
  static const double a = [] {
    double lo = 0.9, hi = 0.98;  // F0(0.9) = 0.980 < 1 < F0(0.98) = 1.0061
    for (int i = 0; i < 200 && hi - lo > 1e-16; ++i) {
      const double mid = 0.5 * (lo + hi);
      (multibounce_F0(mid) < 1.0 ? lo : hi) = mid;
    }
    return lo;
  }();
  return a;
}

double multibounce_alpha_from_ao(double ao) {
  ao = std::clamp(ao, 0.0, 1.0);
  const double a_max = multibounce_alpha_max();
  if (ao >= 1.0) return a_max;
  // Newton on f(α) = F0(α) − ao. F0 is increasing and concave on [0, a_max] and
  // F0(α) <= 1.5 α, so α0 = ao/1.5 lies left of the root and the iterates increase
  // monotonically to it without overshooting.
  double alpha = ao / 1.5;
  for (int i = 0; i < 50; ++i) {
    const double s = 1.0 - alpha;
    const double f = multibounce_F0(alpha) - ao;
    const double df = 1.0 + 0.5 * std::pow(s, 0.75) - 0.375 * alpha * std::pow(s, -0.25);
    const double step = f / df;
    alpha = std::clamp(alpha - step, 0.0, a_max);
    if (std::abs(step) <= 1e-15) break;
  }
  return alpha;
}

namespace {

// F0 + ρ/(1 − ρτ) F1 in the pole-free form, with a = 1 − F0 >= 0 and b = F1 >= 0.
float eq12_channel(double f0, double a, double b, float albedo) {
  const double rho = std::clamp(double(albedo), 0.0, 1.0);
  const double den = (1.0 - rho) * a + rho * b;
  const double bounce = den > 0.0 ? rho * a * b / den : (rho >= 1.0 ? a : 0.0);
  return float(f0 + bounce);
}

Vec3 eq12(double f0, double f1, Vec3 albedo) {
  f0 = std::min(f0, 1.0);
  const double a = 1.0 - f0;
  return {eq12_channel(f0, a, f1, albedo.x), eq12_channel(f0, a, f1, albedo.y),
          eq12_channel(f0, a, f1, albedo.z)};
}

}  // namespace

Vec3 multibounce_eq12(float alpha, Vec3 albedo) {
  const double a = std::clamp(double(alpha), 0.0, 1.0);
  return eq12(multibounce_F0(a), multibounce_F1(a), albedo);
}

Vec3 multibounce_ao(float ao, Vec3 albedo) {
  const double v = std::clamp(double(ao), 0.0, 1.0);
  // The direct term is the measured cosine-weighted AO itself (= F0(α) by construction).
  return eq12(v, multibounce_F1(multibounce_alpha_from_ao(v)), albedo);
}

}  // namespace hbil
