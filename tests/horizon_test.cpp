// horizon_test.cpp: the slice integrals and the horizon search against closed forms.
#include "hbil/horizon.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"
#include "hbil/farfield.h"
#include "hbil/interleave.h"
#include "test_util.h"

namespace hbil {
namespace {

constexpr double kPi = std::numbers::pi;

// Midpoint-rule quadrature of the slice integrals, for comparison with the closed form.
SliceTerms quadrature(double t0, double t1, double nx, double ny) {
  const int n = 20000;
  double ao = 0, vis = 0, bx = 0, by = 0;
  const double h = (t1 - t0) / n;
  for (int k = 0; k < n; ++k) {
    const double t = t0 + (k + 0.5) * h, w = std::fabs(std::sin(t)) * h;
    ao += (nx * std::sin(t) + ny * std::cos(t)) * w;
    vis += w;
    bx += std::sin(t) * w;
    by += std::cos(t) * w;
  }
  return {float(ao), float(vis), float(bx), float(by)};
}

TEST(SliceIntegrals, UnoccludedViewFacingSliceIsOne) {
  const SliceTerms t = integrate_slice(-kPi / 2, kPi / 2, 0.f, 1.f);
  EXPECT_NEAR(t.ao, 1.f, 1e-6);
  EXPECT_NEAR(t.vis, 2.f, 1e-6);  // a half circle of the slice: Ω/2π = 1 after /2
  EXPECT_NEAR(t.bx, 0.f, 1e-6);
  EXPECT_NEAR(t.by, 1.f, 1e-6);
}

TEST(SliceIntegrals, ClosedFormMatchesQuadrature) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-kPi, kPi), a(0, 2 * kPi);
  for (int k = 0; k < 200; ++k) {
    double t0 = u(rng), t1 = u(rng);
    if (t0 > t1) std::swap(t0, t1);
    const double ang = a(rng), len = 0.5 + 0.5 * std::fabs(std::sin(ang * 3));
    const double nx = len * std::sin(ang), ny = len * std::cos(ang);
    const SliceTerms c = integrate_slice(float(t0), float(t1), float(nx), float(ny));
    const SliceTerms q = quadrature(t0, t1, nx, ny);
    EXPECT_NEAR(c.ao, q.ao, 2e-5) << t0 << " " << t1;
    EXPECT_NEAR(c.vis, q.vis, 2e-5);
    EXPECT_NEAR(c.bx, q.bx, 2e-5);
    EXPECT_NEAR(c.by, q.by, 2e-5);
  }
}

Params reference_params() {
  Params p;
  p.method = "horizon";  // the closed forms below assume occluders of infinite thickness
  p.interleave = false;
  p.slices = 32;
  p.steps = 64;
  return p;
}

TEST(HorizonSearch, UnoccludedPlaneHasAoOneAndBentNormalEqualToNormal) {
  // An oblique view of an infinite floor: every pixel is unoccluded.
  const Camera cam = test::look_at(96, 64, 60, {0.3, -4, 2.5}, {0, 0, 0});
  const GBuffer g =
      test::ray_cast(cam, {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{0, 0, 0}, {0, 0, 1}, {0, -1, 0}}});
  for (bool interleave : {false, true}) {
    Params p = reference_params();
    p.interleave = interleave;
    if (interleave) p.slices = 2;
    const AoFrame f = compute_ao_frame(g, cam, p);
    double worst_ao = 0, worst_angle = 0, worst_cone = 0;
    int checked = 0;
    for (size_t i = 0; i < g.pixels(); ++i) {
      if (g.depth[i] > 1e9f) continue;
      ++checked;
      worst_ao = std::max(worst_ao, std::fabs(f.ao[i] - 1.0));
      worst_cone = std::max(worst_cone, double(std::fabs(f.cone_cos[i])));
      worst_angle =
          std::max(worst_angle, double(std::acos(std::min(1.f, dot(f.bent[i], g.normal[i])))));
    }
    EXPECT_GT(checked, 1000);
    // Interleaved pixels average 32 directions only where the whole 4x4 window is valid;
    // on the image border fewer directions remain, hence the looser bound.
    EXPECT_LT(worst_ao, interleave ? 0.03 : 1e-3) << "interleave " << interleave;
    EXPECT_LT(worst_cone, 1e-3) << "interleave " << interleave;
    EXPECT_LT(worst_angle, interleave ? 0.08 : 2e-3) << "interleave " << interleave;
  }
}

TEST(HorizonSearch, ViewFacingPlaneIsExactlyUnoccluded) {
  const Camera cam = test::look_at(64, 48, 50, {0, 0, 3}, {0, 0, 0}, {0, 1, 0});
  const GBuffer g =
      test::ray_cast(cam, {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{0, 0, 0}, {0, 0, 1}, {0, -1, 0}}});
  Params p;  // default: interleaved, 2 slices per pixel
  const AoFrame f = compute_ao_frame(g, cam, p);
  // The centre pixel's view vector is the normal: every slice integrates to exactly 1.
  const size_t c = size_t(24) * 64 + 32;
  EXPECT_NEAR(f.ao[c], 1.f, 1e-5);
  EXPECT_NEAR(dot(f.bent[c], Vec3{0, 0, 1}), 1.f, 1e-5);
}

// Closed forms for a point x on face A of a V-groove of opening γ whose face B is a strip of
// length L, at distance d from the crease, infinite radius. Everything x cannot see lies in
// the lune around the crease-parallel axis through x between face A's plane and the plane
// through B's far edge, tilted ψ = atan2(L sin γ, d − L cos γ) from the direction towards the
// crease. Cosine-weighted (Nusselt analog: a lune tilted ψ projects onto the base as a
// half-ellipse of area π/2 (1 − cos ψ)):  AO = 1 − (1 − cos ψ)/2 = (1 + cos ψ)/2.
// Uniform: a lune of dihedral angle w has solid angle 2w, so Ω/2π = (π − ψ)/π and
// cos α = ψ/π (eq. 12). The bent normal bisects the visible lune: (π + ψ)/2 from the crease
// direction. (L → ∞: ψ = π − γ, AO = (1 − cos γ)/2.)
void check_groove(double gamma_deg) {
  const double gamma = gamma_deg * kPi / 180, L = 1.0;
  const Vec3d bisector{0, std::cos(gamma / 2), std::sin(gamma / 2)};
  const Camera cam = test::look_at(192, 192, 90, bisector * 2.5, bisector * 0.4);
  const GBuffer g = test::ray_cast(cam, test::v_groove(gamma, L));
  Params p = reference_params();
  p.radius = 1e3;  // "infinite": the search is bounded by the screen instead
  p.steps = 192;
  const AoFrame f = compute_ao_frame(g, cam, p);
  int checked = 0;
  // Bounds: AO and bent normal are what we measure plus a margin. The uniform visibility
  // behind cos α weights grazing directions, where the march's coarsest step (about 2.5 px
  // at the end of a 270 px march) can miss B's far edge: measured up to 0.022, bound 0.025.
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const size_t i = size_t(y) * g.width + x;
      if (g.normal[i].z < 0.99f) continue;  // face A only
      const Vec3d hit = cam.view_to_world(cam.unproject(x + 0.5, y + 0.5, g.depth[i]));
      const double d = hit.y;
      if (d < 0.05 || d > 0.6 || std::fabs(hit.x) > 0.3) continue;
      const double psi = std::atan2(L * std::sin(gamma), d - L * std::cos(gamma));
      const double ao_expected = (1 + std::cos(psi)) / 2, cone_expected = psi / kPi;
      const double beta = (kPi + psi) / 2;  // from −y (towards the crease) towards +z
      const Vec3d bent_expected{0, -std::cos(beta), std::sin(beta)};
      ++checked;
      EXPECT_NEAR(f.ao[i], ao_expected, 0.02) << "pixel " << x << "," << y << " d=" << d;
      EXPECT_NEAR(f.cone_cos[i], cone_expected, 0.025) << "pixel " << x << "," << y << " d=" << d;
      EXPECT_GT(dot(Vec3d(f.bent[i]), bent_expected), std::cos(3 * kPi / 180))
          << "pixel " << x << "," << y << " d=" << d;
    }
  EXPECT_GT(checked, 100);
}

TEST(HorizonSearch, RightAngleCornerMatchesClosedForm) {
  check_groove(90);
}
TEST(HorizonSearch, SixtyDegreeGrooveMatchesClosedForm) {
  check_groove(60);
}
TEST(HorizonSearch, HundredTwentyDegreeGrooveMatchesClosedForm) {
  check_groove(120);
}

using test::busy_scene;

TEST(Interleave, DeinterleavedBuffersMatchStridedReadInPlace) {
  Camera cam;
  const GBuffer g = busy_scene(cam);
  const Params p;
  ViewGBuffer v = make_view_gbuffer(g, cam, p);
  const HorizonConfig c = make_horizon_config(p, cam);
  // With a radiance source and a per-pixel thickness too: both must reach the march.
  std::vector<Vec3> radiance(v.pixels());
  v.thickness.assign(v.pixels(), -1.f);
  for (size_t i = 0; i < v.pixels(); ++i) {
    radiance[i] = Vec3{float(i % 7), float(i % 5), 1.f};
    if (i % 3) v.thickness[i] = 0.01f * float(i % 11);
  }
  const HorizonImage a = horizon_interleaved(v, c, 2, &radiance, true),
                     b = horizon_interleaved(v, c, 2, &radiance, false),
                     constant = horizon_interleaved(make_view_gbuffer(g, cam, p), c, 2, &radiance);
  ASSERT_EQ(a.ao.size(), b.ao.size());
  ASSERT_EQ(a.irradiance.size(), b.irradiance.size());
  EXPECT_EQ(0, std::memcmp(a.ao.data(), b.ao.data(), a.ao.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(a.bent.data(), b.bent.data(), a.bent.size() * sizeof(Vec3)));
  EXPECT_EQ(
      0, std::memcmp(a.irradiance.data(), b.irradiance.data(), a.irradiance.size() * sizeof(Vec3)));
  EXPECT_NE(0, std::memcmp(a.ao.data(), constant.ao.data(), a.ao.size() * sizeof(float)))
      << "the per-pixel thickness was not used";
}

TEST(Interleave, BlockCoversEvenlySpacedDirections) {
  std::vector<float> all;
  for (int phase = 0; phase < 16; ++phase) {
    float phi[2];
    interleaved_angles(phase, 2, phi);
    EXPECT_NEAR(phi[1] - phi[0], kPi / 2, 1e-6);  // the paper's 2 slices, 90 degrees apart
    all.insert(all.end(), phi, phi + 2);
  }
  std::sort(all.begin(), all.end());
  for (size_t k = 0; k < all.size(); ++k) EXPECT_NEAR(all[k], kPi * (k + 0.5) / 32, 1e-6);
}

// Every output layer, for both methods, with and without interleaving: the scene has colour
// passes (irradiance, indirect, composite), an environment (farfield) and the multi-bounce
// AO (ao_rgb).
TEST(Determinism, IdenticalBytesForAnyThreadCount) {
  Camera cam;
  GBuffer g = busy_scene(cam);
  g.diffcol.assign(g.pixels(), Vec3{0.8f, 0.5f, 0.2f});
  g.diffdir.assign(g.pixels(), Vec3{});
  for (size_t i = 0; i < g.pixels(); ++i)
    if (g.depth[i] < 1e9f && g.normal[i].z < 0.99f) g.diffdir[i] = Vec3{1, 0.5f, 0.25f};
  const SH9 sky = constant_environment(Vec3{0.2f, 0.3f, 0.5f});
  for (const char* method : {"horizon", "bitmask"})
    for (bool interleave : {true, false}) {
      SCOPED_TRACE(std::string(method) + (interleave ? " interleaved" : " full"));
      Params p;
      p.method = method;
      p.interleave = interleave;
      p.ao_multibounce = true;
      p.outputs = {"ao", "bentcone", "irradiance", "indirect", "composite", "farfield"};
      AoFrame one, many;
      tbb::task_arena(1).execute([&] { one = compute_ao_frame(g, cam, p, &sky); });
      tbb::task_arena(4).execute([&] { many = compute_ao_frame(g, cam, p, &sky); });
      test::expect_same_layers(
          one, many,
          {"ao", "ao_rgb", "bent", "cone_cos", "irradiance", "indirect", "composite", "farfield"});
      // The irradiance is not trivially zero: the lit faces light the others.
      double sum = 0;
      for (const Vec3& e : one.irradiance) sum += e.x;
      EXPECT_GT(sum, 1.0);
    }
}

}  // namespace
}  // namespace hbil
