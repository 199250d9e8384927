// farfield_test.cpp: SH projection of equirectangular environments, Blender's mapping,
// the bent-cone irradiance of HBIL §2.2.4 (hbil/farfield.h), and load_environment
// (io/environment.h).
//
// Tolerances:
//  - closed forms evaluated in float: 1e-4 relative (the brief's), 1e-5 where exact.
//  - SH projection of images: the pixel quadrature of smooth functions (error O(1/h²)).
//  - SH irradiance of a function with detail above order 2: the order-2 truncation error,
//    computed below from the closed-form SH coefficients of the function.
#include "hbil/farfield.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "hbil/error.h"
#include "io/environment.h"
#include "test_util.h"

namespace hbil {
namespace {

constexpr double kPi = std::numbers::pi;

// An equirectangular image of w x h pixels (top row first) of the radiance f(direction),
// sampled at pixel centres with Blender's mapping.
std::vector<float> make_equirect(int w, int h, const std::function<Vec3d(const Vec3d&)>& f) {
  std::vector<float> img(size_t(w) * h * 3);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const Vec3d d = equirect_to_direction((i + 0.5) / w, 1.0 - (j + 0.5) / h);
      const Vec3d v = f(d);
      float* px = &img[(size_t(j) * w + i) * 3];
      px[0] = float(v.x), px[1] = float(v.y), px[2] = float(v.z);
    }
  return img;
}

// ∫_{ω·n >= t} g(ω) (n·ω) dω by quadrature in a frame around n: midpoint rule in μ = n·ω on
// [t, 1] and in φ. For g a polynomial of degree <= 2 in ω the φ sum (nphi >= 3) is exact
// and the μ integrand a cubic, so the error is the midpoint rule's O(1/nmu²).
double cone_quadrature(const std::function<double(const Vec3d&)>& g, Vec3d n, double t,
                       int nmu = 4000, int nphi = 64) {
  const Vec3d a = std::abs(n.z) < 0.9 ? Vec3d(0, 0, 1) : Vec3d(1, 0, 0);
  const Vec3d e1 = normalize_or_zero(cross(a, n)), e2 = cross(n, e1);
  double sum = 0;
  const double dmu = (1.0 - t) / nmu, dphi = 2.0 * kPi / nphi;
  for (int i = 0; i < nmu; ++i) {
    const double mu = t + (i + 0.5) * dmu, s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    for (int k = 0; k < nphi; ++k) {
      const double phi = (k + 0.5) * dphi;
      const Vec3d w = n * mu + e1 * (s * std::cos(phi)) + e2 * (s * std::sin(phi));
      sum += g(w) * mu;
    }
  }
  return sum * dmu * dphi;
}

Vec3d dipole_direction(const SH9& sh, int channel = 0) {
  // L1-1 ~ y, L10 ~ z, L11 ~ x.
  return normalize_or_zero(Vec3d(sh.c[3][channel], sh.c[1][channel], sh.c[2][channel]));
}

double angle_deg(Vec3d a, Vec3d b) {
  return std::acos(std::clamp(dot(normalize_or_zero(a), normalize_or_zero(b)), -1.0, 1.0)) * 180.0 /
         kPi;
}

// ---------------------------------------------------------------------------------------
// Mapping

TEST(Farfield, BlenderEquirectMapping) {
  // Cycles direction_to_equirectangular: u = 0.5 − atan2(y, x)/2π, v = 0.5 + latitude/π.
  struct Case {
    Vec3d d;
    double u, v;
  } cases[] = {{{1, 0, 0}, 0.5, 0.5},    // image centre looks along +X
               {{0, 1, 0}, 0.25, 0.5},   // a quarter from the left: +Y
               {{0, -1, 0}, 0.75, 0.5},  // three quarters: −Y
               {{0, 0, 1}, 0.5, 1.0},    // top row: zenith
               {{0, 0, -1}, 0.5, 0.0}};  // bottom row: nadir
  for (const auto& c : cases) {
    double u, v;
    direction_to_equirect(c.d, u, v);
    EXPECT_NEAR(u, c.u, 1e-12) << c.d.x << " " << c.d.y << " " << c.d.z;
    EXPECT_NEAR(v, c.v, 1e-12);
  }
  double u, v;
  direction_to_equirect({-1, 0, 0}, u, v);  // the seam
  EXPECT_NEAR(std::min(u, 1.0 - u), 0.0, 1e-12);
  // Round trip over the whole square.
  for (double uu = 0.01; uu < 1; uu += 0.049)
    for (double vv = 0.01; vv < 1; vv += 0.049) {
      const Vec3d d = equirect_to_direction(uu, vv);
      EXPECT_NEAR(length(d), 1.0, 1e-12);
      direction_to_equirect(d, u, v);
      EXPECT_NEAR(u, uu, 1e-12);
      EXPECT_NEAR(v, vv, 1e-12);
    }
}

// ---------------------------------------------------------------------------------------
// Constant environment

TEST(Farfield, ConstantEnvironmentIsL00Only) {
  const Vec3 L(0.25f, 1.0f, 3.0f);
  const SH9 sh = constant_environment(L);
  const double k = 2.0 * std::sqrt(kPi);  // ∫ L Y00 dω = 4π L /(2√π)
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sh.c[0][ch], k * L[ch], 1e-6 * k * L[ch]);
  for (int i = 1; i < 9; ++i)
    for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(sh.c[i][ch], 0.0f);
}

TEST(Farfield, ProjectConstantImage) {
  const Vec3 L(0.5f, 2.0f, 7.0f);
  for (auto [w, h] : {std::pair{64, 32}, {7, 3}, {1, 1}, {512, 256}}) {
    const auto img = make_equirect(w, h, [&](const Vec3d&) { return Vec3d(L); });
    const SH9 sh = project_equirect(img.data(), w, h);
    const double k = 2.0 * std::sqrt(kPi);
    for (int ch = 0; ch < 3; ++ch) {
      // Exact solid-angle weights: L00 is exact at any resolution.
      EXPECT_NEAR(sh.c[0][ch], k * L[ch], 1e-5 * k * L[ch]) << w << "x" << h;
      // Higher bands: zero by symmetry of the pixel grid.
      for (int i = 1; i < 9; ++i) EXPECT_NEAR(sh.c[i][ch], 0.0, 1e-5 * k * L[ch]) << i;
    }
  }
}

TEST(Farfield, ConeIrradianceOfConstantIsPiLSin2) {
  const Vec3 L(0.5f, 1.0f, 4.0f);
  const SH9 sh = constant_environment(L);
  for (double deg : {90.0, 80.0, 60.0, 45.0, 30.0, 10.0, 2.0, 0.5}) {
    const float t = float(std::cos(deg * kPi / 180.0));
    const double sin2 = 1.0 - double(t) * double(t);  // sin²θmax of the cone t describes
    for (Vec3 n : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(0.6f, 0.0f, 0.8f), Vec3(0, 1, 0)}) {
      const Vec3 e = cone_irradiance(sh, n, t);
      for (int ch = 0; ch < 3; ++ch) {
        const double want = kPi * L[ch] * sin2;
        EXPECT_NEAR(e[ch], want, 1e-4 * want) << deg << " deg, channel " << ch;
      }
    }
  }
  // Full hemisphere: E = π L.
  const Vec3 e = cone_irradiance(sh, {0, 0, 1}, 0.0f);
  EXPECT_NEAR(e.y, kPi, 1e-6 * kPi);
  // t outside [0, 1] is clamped: wider than the hemisphere counts as the hemisphere, t > 1
  // as an empty cone.
  EXPECT_FLOAT_EQ(cone_irradiance(sh, {0, 0, 1}, -0.5f).y, e.y);
  EXPECT_EQ(cone_irradiance(sh, {0, 0, 1}, 1.5f).y, 0.0f);
}

TEST(Farfield, PaperCoefficientsMatchDerivation) {
  // c0 = A_0, c1 = A_1, c2 = A_2/2 with A_l = 2π ∫_t^1 Y_l0(μ) μ dμ (farfield.cpp), here
  // integrated numerically; at t = 0 R&H's Â_0 = π, Â_1 = 2π/3, Â_2 = π/4.
  for (double t_in : {0.0, 0.2, 0.5, 0.8, 0.95, 0.999}) {
    const double t = double(float(t_in));  // the t the float function sees
    double a[3] = {0, 0, 0};
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      const double mu = t + (i + 0.5) * (1.0 - t) / n;
      double Y[9];
      sh9_basis({std::sqrt(1 - mu * mu), 0, mu}, Y);
      a[0] += Y[0] * mu, a[1] += Y[2] * mu, a[2] += Y[6] * mu;
    }
    for (double& x : a) x *= 2.0 * kPi * (1.0 - t) / n;
    float c0, c1, c2;
    cone_sh_coefficients(float(t), c0, c1, c2);
    EXPECT_NEAR(c0, a[0], 1e-5 * std::abs(a[0]) + 1e-9) << t;
    EXPECT_NEAR(c1, a[1], 1e-5 * std::abs(a[1]) + 1e-9) << t;
    EXPECT_NEAR(c2, a[2] / 2, 1e-5 * std::abs(a[2] / 2) + 1e-9) << t;
    if (t == 0.0) {
      EXPECT_NEAR(std::sqrt(4 * kPi) * a[0], kPi, 1e-6);
      EXPECT_NEAR(std::sqrt(4 * kPi / 3) * a[1], 2 * kPi / 3, 1e-6);
      EXPECT_NEAR(std::sqrt(4 * kPi / 5) * a[2], kPi / 4, 1e-6);
    }
  }
}

TEST(Farfield, ConeIrradianceExactForOrder2Radiance) {
  // For a radiance that is itself an order-2 SH expansion the formula has no truncation
  // error: it must equal ∫_cone L(ω)(n·ω) dω for every n and t, exercising all 9 terms.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  SH9 sh;
  double a[9];
  a[0] = 6.0;  // keeps L and E positive
  for (int k = 1; k < 9; ++k) a[k] = U(rng);
  for (int k = 0; k < 9; ++k) sh.c[k] = Vec3(float(a[k]), float(0.5 * a[k]), 0.0f);
  sh.c[0].z = float(a[0]);
  const auto L = [&](const Vec3d& w) {
    double Y[9];
    sh9_basis(w, Y);
    double s = 0;
    for (int k = 0; k < 9; ++k) s += a[k] * Y[k];
    return s;
  };
  for (int trial = 0; trial < 12; ++trial) {
    const Vec3d n = normalize_or_zero(Vec3d(U(rng), U(rng), U(rng)));
    for (double t : {0.0, 0.3, 0.7, 0.95}) {
      const double want = cone_quadrature(L, n, t);
      const Vec3 e = cone_irradiance(sh, Vec3(n), float(t));
      EXPECT_NEAR(e.x, want, 2e-5 * std::abs(want) + 1e-6) << "trial " << trial << " t " << t;
      // Channel z holds only L00: π L00/(2√π) (1 − t²).
      EXPECT_NEAR(e.z, a[0] / (2 * std::sqrt(kPi)) * kPi * (1 - t * t), 1e-5 * a[0]);
    }
  }
}

// ---------------------------------------------------------------------------------------
// A direction-dependent environment: L(ω) = max(0, ω·z), a clamped cosine around +Z.

TEST(Farfield, ClampedCosineSkyProjection) {
  const int w = 512, h = 256;
  const auto img = make_equirect(w, h, [](const Vec3d& d) {
    const double v = std::max(0.0, d.z);
    return Vec3d(v, 2 * v, 0.5 * v);
  });
  const SH9 sh = project_equirect(img.data(), w, h);
  // Closed forms: L_l0 = 2π ∫_0^1 Y_l0(μ) μ dμ; the other coefficients vanish.
  const double l00 = std::sqrt(kPi) / 2, l10 = std::sqrt(kPi / 3), l20 = std::sqrt(5 * kPi) / 8;
  const double want[9] = {l00, 0, l10, 0, 0, 0, l20, 0, 0};
  for (int k = 0; k < 9; ++k) {
    EXPECT_NEAR(sh.c[k].x, want[k], 1e-4) << k;
    EXPECT_NEAR(sh.c[k].y, 2 * want[k], 2e-4) << k;
    EXPECT_NEAR(sh.c[k].z, 0.5 * want[k], 0.5e-4) << k;
  }
}

TEST(Farfield, ClampedCosineSkyIrradiance) {
  const int w = 512, h = 256;
  const auto img = make_equirect(w, h, [](const Vec3d& d) {
    const double v = std::max(0.0, d.z);
    return Vec3d(v, v, v);
  });
  const SH9 sh = project_equirect(img.data(), w, h);
  const auto sky = [](const Vec3d& d) { return std::max(0.0, d.z); };
  // Order-2 value in closed form: E2(n) = Σ_l Â_l L_l0 Y_l0(n), Â = (π, 2π/3, π/4).
  const double l00 = std::sqrt(kPi) / 2, l10 = std::sqrt(kPi / 3), l20 = std::sqrt(5 * kPi) / 8;
  const auto e2 = [&](Vec3d n) {
    double Y[9];
    sh9_basis(n, Y);
    return kPi * l00 * Y[0] + 2 * kPi / 3 * l10 * Y[2] + kPi / 4 * l20 * Y[6];
  };
  struct Case {
    Vec3d n;
    double exact;  // analytic ∫_H(n) max(0, ω_z)(n·ω) dω
  } cases[] = {{{0, 0, 1}, 2 * kPi / 3}, {{0, 0, -1}, 0.0}, {{1, 0, 0}, 2.0 / 3.0}};
  for (const auto& c : cases) {
    const double quad = cone_quadrature(sky, c.n, 0.0, 8000, 512);
    EXPECT_NEAR(quad, c.exact, 2e-4) << "quadrature check";
    const double e = cone_irradiance(sh, Vec3(c.n), 0.0f).x;
    // The projection and the formula reproduce the order-2 value (clamped at 0)...
    EXPECT_NEAR(e, std::max(0.0, e2(c.n)), 2e-4) << c.n.x << " " << c.n.z;
    // ...which misses the l >= 4 bands: 0.0164 (0.78%) at ±z, 0.0040 at +x.
    const double truncation = std::abs(e2(c.n) - quad);
    EXPECT_LT(truncation, 0.0165);
    EXPECT_NEAR(e, quad, truncation + 2e-4) << c.n.x << " " << c.n.z;
  }
  EXPECT_NEAR(e2({0, 0, 1}) - 2 * kPi / 3, -0.01636, 1e-4);
  EXPECT_NEAR(e2({1, 0, 0}) - 2.0 / 3.0, -0.00400, 1e-4);
}

TEST(Farfield, ClampedCosineSkyConeIrradiance) {
  // Narrowing the cone around +z. The order-2 estimate reproduces its closed form
  // E2(t) = c0 L00 + c1 L10 + 2 c2 L20, and differs from the exact 2π(1 − t³)/3 by the l >= 3
  // bands the cone kernel passes: −0.0164 (t = 0), −0.0206 (0.3), +0.0084 (0.6),
  // +0.0254 (0.9, 4.5%): narrow cones are less band-limited than the hemisphere.
  const int w = 512, h = 256;
  const auto img = make_equirect(w, h, [](const Vec3d& d) {
    const double v = std::max(0.0, d.z);
    return Vec3d(v, v, v);
  });
  const SH9 sh = project_equirect(img.data(), w, h);
  const auto sky = [](const Vec3d& d) { return std::max(0.0, d.z); };
  const double l00 = std::sqrt(kPi) / 2, l10 = std::sqrt(kPi / 3), l20 = std::sqrt(5 * kPi) / 8;
  const double truncation[] = {-0.016362, -0.020559, 0.008378, 0.025386};
  int k = 0;
  for (double t : {0.0, 0.3, 0.6, 0.9}) {
    const double exact = 2 * kPi * (1 - t * t * t) / 3;
    EXPECT_NEAR(cone_quadrature(sky, {0, 0, 1}, t), exact, 1e-5);
    float c0, c1, c2;
    cone_sh_coefficients(float(t), c0, c1, c2);
    const double e2 = c0 * l00 + c1 * l10 + 2 * c2 * l20;
    EXPECT_NEAR(e2 - exact, truncation[k++], 1e-5) << t;
    EXPECT_NEAR(cone_irradiance(sh, {0, 0, 1}, float(t)).x, e2, 2e-4) << t;
  }
}

// ---------------------------------------------------------------------------------------
// Orientation: a bright block lands where Blender's mapping says.

struct Block {
  int i0, j0, size;  // top-left pixel and side
};

std::vector<float> block_image(int w, int h, Block b, float value = 100.0f) {
  std::vector<float> img(size_t(w) * h * 3, 0.0f);
  for (int j = b.j0; j < b.j0 + b.size; ++j)
    for (int i = b.i0; i < b.i0 + b.size; ++i)
      for (int c = 0; c < 3; ++c) img[(size_t(j) * w + i) * 3 + c] = value;
  return img;
}

Vec3d block_direction(int w, int h, Block b) {
  return equirect_to_direction((b.i0 + 0.5 * b.size) / w, 1.0 - (b.j0 + 0.5 * b.size) / h);
}

TEST(Farfield, BrightBlockOrientation) {
  const int w = 128, h = 64;
  struct Case {
    Block b;
    Vec3d expected;  // from the mapping, stated by hand
  } cases[] = {
      {{62, 14, 4}, {std::cos(kPi / 4), 0, std::sin(kPi / 4)}},    // centre column, 45° up: +X
      {{30, 14, 4}, {0, std::cos(kPi / 4), std::sin(kPi / 4)}},    // u = 1/4: +Y
      {{94, 14, 4}, {0, -std::cos(kPi / 4), std::sin(kPi / 4)}},   // u = 3/4: −Y
      {{30, 46, 4}, {0, std::cos(kPi / 4), -std::sin(kPi / 4)}},   // lower half: below horizon
      {{0, 31, 2}, {-std::cos(kPi / 64), std::sin(kPi / 64), 0}},  // left edge, horizon: −X
  };
  for (const auto& c : cases) {
    EXPECT_LT(angle_deg(block_direction(w, h, c.b), c.expected), 1e-9);
    const auto img = block_image(w, h, c.b);
    const SH9 sh = project_equirect(img.data(), w, h);
    const Vec3d d = dipole_direction(sh);
    // The cos-latitude weight pulls the mean direction slightly towards the equator.
    EXPECT_LT(angle_deg(d, c.expected), 0.5) << c.b.i0 << "," << c.b.j0;
    // Irradiance through a narrow cone peaks there, not at the u- or v-mirrored directions.
    const Vec3 n(d);
    const float e = cone_irradiance(sh, n, 0.9f).x;
    for (Vec3 m : {Vec3(n.x, -n.y, n.z), Vec3(-n.x, n.y, n.z), Vec3(n.x, n.y, -n.z)})
      if (angle_deg(Vec3d(m), d) > 10.0) {
        EXPECT_GT(e, 1.5f * cone_irradiance(sh, m, 0.9f).x);
      }
  }
}

// ---------------------------------------------------------------------------------------
// Properties and errors

TEST(Farfield, ProjectionIsThreadCountIndependent) {
  const int w = 256, h = 128;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(0, 10);
  std::vector<float> img(size_t(w) * h * 3);
  for (float& v : img) v = U(rng);
  SH9 one, many;
  {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
    one = project_equirect(img.data(), w, h);
  }
  many = project_equirect(img.data(), w, h);
  EXPECT_EQ(std::memcmp(&one, &many, sizeof(SH9)), 0);
}

TEST(Farfield, ProjectErrors) {
  const std::vector<float> img(12, 1.0f);
  test::expect_error([&] { project_equirect(img.data(), 0, 2); }, Exit::bad_data, {"0 x 2"});
  std::vector<float> bad(size_t(4) * 2 * 3, 1.0f);
  bad[(size_t(1) * 4 + 3) * 3 + 1] = std::nanf("");
  test::expect_error([&] { project_equirect(bad.data(), 4, 2); }, Exit::bad_data,
                     {"(3, 1)", "not finite"});
}

// ---------------------------------------------------------------------------------------
// load_environment

TEST(Environment, ConstantSpec) {
  const SH9 sh = io::load_environment("rgb:0.1,0.2,0.3");
  const double k = 2.0 * std::sqrt(kPi);
  EXPECT_NEAR(sh.c[0].x, 0.1 * k, 1e-6);
  EXPECT_NEAR(sh.c[0].y, 0.2 * k, 1e-6);
  EXPECT_NEAR(sh.c[0].z, 0.3 * k, 1e-6);
  for (int i = 1; i < 9; ++i) EXPECT_EQ(sh.c[i].x + sh.c[i].y + sh.c[i].z, 0.0f);
  EXPECT_NEAR(cone_irradiance(sh, {0, 0, 1}, 0.0f).z, kPi * 0.3, 1e-5);
  EXPECT_NEAR(io::load_environment("rgb:1e-2,0,2.5").c[0].z, 2.5 * k, 1e-5);
}

TEST(Environment, MalformedConstantSpec) {
  for (const char* s : {"rgb:", "rgb:0.1,0.2", "rgb:a,b,c", "rgb:0.1,0.2,0.3,", "rgb:0.1,0.2,0.3x",
                        "rgb:-1,0,0", "rgb:0.1;0.2;0.3", "rgb:inf,0,0", "rgb: 0.1,0.2,0.3"})
    test::expect_error([&] { io::load_environment(s); }, Exit::usage, {s, "rgb:R,G,B"});
}

TEST(Environment, ReadsExrByChannelName) {
  test::TempDir dir(test::test_name());
  const int w = 64, h = 32;
  // Channels in an order other than R, G, B; values per channel.
  const std::string path = dir / "env.exr";
  test::write_exr(path, w, h, {"A", "B", "G", "R"}, [](int, int, int c) {
    return c == 0 ? 9.0f : c == 1 ? 0.125f : c == 2 ? 0.25f : 0.5f;
  });
  const SH9 sh = io::load_environment(path);
  const double k = 2.0 * std::sqrt(kPi);
  EXPECT_NEAR(sh.c[0].x, 0.5 * k, 1e-5);
  EXPECT_NEAR(sh.c[0].y, 0.25 * k, 1e-5);
  EXPECT_NEAR(sh.c[0].z, 0.125 * k, 1e-5);
}

TEST(Environment, ReadsFirstThreeChannelsAndKeepsOrientation) {
  // A bright block towards +Y, 45° up, in a file: checks that no row or column flip happens
  // between the file and the projection.
  test::TempDir dir(test::test_name());
  const int w = 128, h = 64;
  const Block b{30, 14, 4};
  const auto img = block_image(w, h, b);
  const std::string path = dir / "block.exr";
  test::write_exr(path, w, h, {"X", "Y", "Z"},
                  [&](int x, int y, int c) { return img[(size_t(y) * w + x) * 3 + c]; });
  const SH9 sh = io::load_environment(path);
  EXPECT_LT(angle_deg(dipole_direction(sh), {0, std::cos(kPi / 4), std::sin(kPi / 4)}), 1.0);
  const SH9 direct = project_equirect(img.data(), w, h);
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(sh.c[k].x, direct.c[k].x, 1e-6 * std::abs(direct.c[0].x));
}

TEST(Environment, ReadsRadianceHdr) {
  test::TempDir dir(test::test_name());
  const int w = 32, h = 16;
  const std::string path = dir / "env.hdr";
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
  std::vector<float> px(size_t(w) * h * 3);
  for (size_t i = 0; i < px.size(); ++i) px[i] = i % 3 == 0 ? 1.5f : i % 3 == 1 ? 0.75f : 3.0f;
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << out->geterror();
  ASSERT_TRUE(out->close());
  const SH9 sh = io::load_environment(path);
  const double k = 2.0 * std::sqrt(kPi);
  // RGBE keeps 8 bits of mantissa: 1%.
  EXPECT_NEAR(sh.c[0].x, 1.5 * k, 0.01 * 1.5 * k);
  EXPECT_NEAR(sh.c[0].y, 0.75 * k, 0.01 * 0.75 * k);
  EXPECT_NEAR(sh.c[0].z, 3.0 * k, 0.01 * 3.0 * k);
}

TEST(Environment, Errors) {
  test::TempDir dir(test::test_name());
  const std::string missing = dir / "nope.exr";
  test::expect_error([&] { io::load_environment(missing); }, Exit::input, {missing, "not found"});
  const std::string text = dir / "text.exr";
  test::write_text(text, "not an image");
  test::expect_error([&] { io::load_environment(text); }, Exit::input, {text, "cannot read"});
  const std::string square = dir / "square.exr";
  test::write_exr(square, 32, 32, {"R", "G", "B"}, [](int, int, int) { return 1.0f; });
  test::expect_error([&] { io::load_environment(square); }, Exit::bad_data,
                     {square, "32 x 32", "width = 2 x height"});
  const std::string two = dir / "two.exr";
  test::write_exr(two, 32, 16, {"R", "G"}, [](int, int, int) { return 1.0f; });
  test::expect_error([&] { io::load_environment(two); }, Exit::bad_data, {two, "2 channel"});
  const std::string nan = dir / "nan.exr";
  test::write_exr(nan, 32, 16, {"R", "G", "B"},
                  [](int x, int y, int c) { return x == 5 && y == 7 ? NAN : 1.0f; });
  test::expect_error([&] { io::load_environment(nan); }, Exit::bad_data,
                     {nan, "(5, 7)", "not finite"});
  test::expect_error([&] { io::load_environment(""); }, Exit::usage, {"empty"});
}

}  // namespace
}  // namespace hbil
