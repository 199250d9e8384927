// farfield.cpp: see farfield.h.
#include "hbil/farfield.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "hbil/error.h"

namespace hbil {

namespace {

constexpr double kPi = std::numbers::pi;

}  // namespace

void sh9_basis(const Vec3d& d, double Y[9]) {
  // R&H 2001 eq. 3.
  static const double k0 = 0.5 / std::sqrt(kPi);             // 1/(2√π)
  static const double k1 = std::sqrt(3.0 / (4.0 * kPi));     // l = 1
  static const double k2 = std::sqrt(15.0 / (4.0 * kPi));    // (2,-2), (2,-1), (2,1)
  static const double k20 = std::sqrt(5.0 / (16.0 * kPi));   // (2, 0)
  static const double k22 = std::sqrt(15.0 / (16.0 * kPi));  // (2, 2)
  Y[0] = k0;
  Y[1] = k1 * d.y;
  Y[2] = k1 * d.z;
  Y[3] = k1 * d.x;
  Y[4] = k2 * d.x * d.y;
  Y[5] = k2 * d.y * d.z;
  Y[6] = k20 * (3.0 * d.z * d.z - 1.0);
  Y[7] = k2 * d.x * d.z;
  Y[8] = k22 * (d.x * d.x - d.y * d.y);
}

// Cycles equirectangular_to_direction: φ = −2πu + π (azimuth from +X towards +Y),
// θ = −πv + π (polar angle from +Z).
Vec3d equirect_to_direction(double u, double v) {
  const double phi = kPi - 2.0 * kPi * u;
  const double theta = kPi - kPi * v;
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Cycles direction_to_equirectangular / EEVEE node_tex_environment_equirectangular.
void direction_to_equirect(const Vec3d& d, double& u, double& v) {
  u = 0.5 - std::atan2(d.y, d.x) / (2.0 * kPi);
  v = 0.5 + std::atan2(d.z, std::hypot(d.x, d.y)) / kPi;
}

// Each pixel is taken as constant over its latitude-longitude rectangle, and the basis is
// integrated over that rectangle in closed form. With s = sin(latitude), dω = ds dφ and
// x = cos(lat) cos φ, y = cos(lat) sin φ, z = s, every basis function factors into a latitude
// integral (per row) times an azimuth integral (per column):
//   Y00:  R0 C0       R0  = ∫ ds = Δs                      C0  = Δφ
//   y,x:  Rc Cs, Rc Cc  Rc = ∫ cos(lat) ds = ∫ cos² dlat  Cs, Cc = ∫ sin φ, ∫ cos φ dφ
//   z:    Rs C0       Rs  = ∫ s ds
//   xy:   Rcc C2s/2   Rcc = ∫ (1 − s²) ds                  C2s, C2c = ∫ sin 2φ, ∫ cos 2φ dφ
//   yz,xz: Rsc Cs, Rsc Cc  Rsc = ∫ s cos(lat) ds = ∫ sin cos² dlat
//   3z²−1: R20 C0     R20 = ∫ (3s² − 1) ds
//   x²−y²: Rcc C2c
SH9 project_equirect(const float* rgb, int width, int height) {
  if (width < 1 || height < 1) {
    std::ostringstream m;
    m << "environment image is " << width << " x " << height << " pixels; it needs at least 1 x 1";
    throw Error(Exit::bad_data, m.str());
  }
  const size_t w = size_t(width), h = size_t(height);
  static const double k0 = 0.5 / std::sqrt(kPi), k1 = std::sqrt(3.0 / (4.0 * kPi)),
                      k2 = std::sqrt(15.0 / (4.0 * kPi)), k20 = std::sqrt(5.0 / (16.0 * kPi)),
                      k22 = std::sqrt(15.0 / (16.0 * kPi));
  // Azimuth integrals per column. Column i spans u in [i/w, (i+1)/w], i.e. φ = π − 2πu in
  // [φa, φb] = [π − 2π(i+1)/w, π − 2πi/w].
  struct Col {
    double c0, cc, cs, c2c, c2s;
  };
  std::vector<Col> cols(w);
  for (size_t i = 0; i < w; ++i) {
    const double pa = kPi - 2.0 * kPi * double(i + 1) / double(w);
    const double pb = kPi - 2.0 * kPi * double(i) / double(w);
    cols[i] = {pb - pa, std::sin(pb) - std::sin(pa), std::cos(pa) - std::cos(pb),
               0.5 * (std::sin(2 * pb) - std::sin(2 * pa)),
               0.5 * (std::cos(2 * pa) - std::cos(2 * pb))};
  }
  // One partial sum per row, summed afterwards in row order: the same bytes on any number of
  // threads. Per row: 9 coefficients x 3 channels.
  std::vector<std::array<double, 27>> rows(h);
  std::vector<long long> bad(h, -1);  // first non-finite pixel of each row, or -1
  tbb::parallel_for(size_t(0), h, [&](size_t j) {
    // Row j (from the top) spans latitudes [l0, l1].
    const double l1 = kPi * (0.5 - double(j) / double(h));
    const double l0 = kPi * (0.5 - double(j + 1) / double(h));
    const double s0 = std::sin(l0), s1 = std::sin(l1);
    const double c0 = std::cos(l0), c1 = std::cos(l1);
    const double r0 = s1 - s0;
    const double rc = 0.5 * (l1 - l0) + 0.25 * (std::sin(2 * l1) - std::sin(2 * l0));
    const double rs = 0.5 * (s1 * s1 - s0 * s0);
    const double r3 = s1 * s1 * s1 - s0 * s0 * s0;
    const double rcc = r0 - r3 / 3.0;
    const double rsc = (c0 * c0 * c0 - c1 * c1 * c1) / 3.0;
    const double r20 = r3 - r0;
    std::array<double, 27> acc{};
    const float* row = rgb + j * w * 3;
    for (size_t i = 0; i < w; ++i) {
      const float* px = row + i * 3;
      if (!std::isfinite(px[0]) || !std::isfinite(px[1]) || !std::isfinite(px[2])) {
        if (bad[j] < 0) bad[j] = (long long)(i);
        continue;
      }
      const Col& c = cols[i];
      const double Y[9] = {k0 * r0 * c.c0,   k1 * rc * c.cs,         k1 * rs * c.c0,
                           k1 * rc * c.cc,   k2 * rcc * 0.5 * c.c2s, k2 * rsc * c.cs,
                           k20 * r20 * c.c0, k2 * rsc * c.cc,        k22 * rcc * c.c2c};
      for (int k = 0; k < 9; ++k) {
        acc[k * 3 + 0] += Y[k] * px[0];
        acc[k * 3 + 1] += Y[k] * px[1];
        acc[k * 3 + 2] += Y[k] * px[2];
      }
    }
    rows[j] = acc;
  });
  for (size_t j = 0; j < h; ++j)
    if (bad[j] >= 0) {
      const size_t i = size_t(bad[j]);
      const float* px = rgb + (j * w + i) * 3;
      std::ostringstream m;
      m << "environment pixel (" << i << ", " << j << ") is not finite: (" << px[0] << ", " << px[1]
        << ", " << px[2] << ")";
      throw Error(Exit::bad_data, m.str());
    }
  std::array<double, 27> sum{};
  for (size_t j = 0; j < h; ++j)
    for (int k = 0; k < 27; ++k) sum[k] += rows[j][k];
  SH9 sh;
  for (int k = 0; k < 9; ++k)
    sh.c[k] = Vec3(float(sum[k * 3 + 0]), float(sum[k * 3 + 1]), float(sum[k * 3 + 2]));
  return sh;
}

SH9 constant_environment(Vec3 L) {
  SH9 sh;
  sh.c[0] = L * float(2.0 * std::sqrt(kPi));  // ∫ L Y_00 dω = 4π L /(2√π)
  return sh;
}

// HBIL §2.2.4. With μ = cos θ and A_l(t) = 2π ∫_t^1 Y_l0(μ) μ dμ:
//   A_0 = 2π (1/(2√π)) (1 − t²)/2                        = (√π/2)(1 − t²)          = c0
//   A_1 = 2π √(3/4π) (1 − t³)/3                          = (√(3π)/3)(1 − t³)        = c1
//   A_2 = 2π √(5/16π) [3(1 − t⁴)/4 − (1 − t²)/2]         = (√(5π)/8)[3(1−t⁴) − 2(1−t²)]
// The irradiance is E(n) = Σ_lm √(4π/(2l+1)) A_l L_lm Y_lm(n) (R&H 2001 eq. 7-8, with the
// integral's bound moved to θmax). Expanding Y_lm(n):
//   l = 0: √(4π) A_0 · 1/(2√π)          = A_0                → c0 L00
//   l = 1: √(4π/3) A_1 · √(3/4π)        = A_1                → c1 (y L1-1 + z L10 + x L11)
//   l = 2, m = 0: √(4π/5) A_2 √(5/16π)  = A_2/2              → c2 L20 (3z² − 1)
//   l = 2, m = 2: √(4π/5) A_2 √(15/16π) = (√3/2) A_2 = √3 c2 → √3 c2 L22 (x² − y²)
//   l = 2, |m| = 1 and m = −2: √(4π/5) A_2 √(15/4π) = √3 A_2 = 2√3 c2
// hence c2 = A_2/2 = (√(5π)/4)[3(1−t⁴) − 2(1−t²)]/4, the paper's value.
void cone_sh_coefficients(float t, float& c0, float& c1, float& c2) {
  t = std::clamp(t, 0.0f, 1.0f);
  // The paper's expressions, factored through (1 − t) so that narrow cones (t -> 1) keep
  // their relative precision in float: 1 − t² = (1 − t)(1 + t), 1 − t³ = (1 − t)(1 + t + t²),
  // 3(1 − t⁴) − 2(1 − t²) = (1 − t²)(1 + 3t²).
  const float one_minus_t = 1.0f - t;
  const float one_minus_t2 = one_minus_t * (1.0f + t);
  const float one_minus_t3 = one_minus_t * (1.0f + t + t * t);
  c0 = float(0.5 * std::sqrt(kPi)) * one_minus_t2;
  c1 = float(std::sqrt(3.0 * kPi) / 3.0) * one_minus_t3;
  c2 = float(std::sqrt(5.0 * kPi) / 16.0) * one_minus_t2 * (1.0f + 3.0f * t * t);
}

Vec3 cone_irradiance(const SH9& L, Vec3 n, float cos_theta_max) {
  float c0, c1, c2;
  cone_sh_coefficients(cos_theta_max, c0, c1, c2);
  const float x = n.x, y = n.y, z = n.z;
  const float sqrt3 = 1.7320508075688772f;
  const Vec3* c = L.c;
  Vec3 e = c[0] * c0                                // L00
           + (c[1] * y + c[2] * z + c[3] * x) * c1  // L1-1, L10, L11
           + c[6] * (c2 * (3.0f * z * z - 1.0f))    // L20
           + c[8] * (c2 * sqrt3 * (x * x - y * y))  // L22
           + (c[4] * (x * y) + c[5] * (y * z) + c[7] * (z * x)) * (2.0f * sqrt3 * c2);
  return {std::max(e.x, 0.0f), std::max(e.y, 0.0f), std::max(e.z, 0.0f)};
}

}  // namespace hbil
