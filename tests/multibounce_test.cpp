// multibounce_test.cpp: multi-bounce AO (hbil/multibounce.h) against the improved-AO notes'
// eq. 7, 9, 11, 12 as printed, and the properties the model must have.
#include "hbil/multibounce.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hbil {
namespace {

// Eq. 12 / E_0 exactly as printed, with τ from eq. 9 (poles and 0/0 included).
double printed_eq12(double alpha, double rho) {
  const double A = 27.576937094210385, B = 3.3364392003423804;
  const double f0 = alpha * (1 + std::pow(1 - alpha, 0.75) / 2);  // eq. 7
  const double f1 =
      A * alpha * std::pow(1 - alpha, 1.5) * std::exp(-B * std::pow(alpha, 0.25));  // eq. 11
  const double tau = 1 - f1 / (1 - f0);                                             // eq. 9
  return f0 + rho / (1 - rho * tau) * f1;                                           // eq. 12
}

const float kAlbedos[] = {0.0f, 0.05f, 0.2f, 0.5f, 0.8f, 0.95f, 1.0f};

TEST(Multibounce, ConstantsAsPrinted) {
  static_assert(kMultibounceA == 27.576937094210385);
  static_assert(kMultibounceB == 3.3364392003423804);
  EXPECT_DOUBLE_EQ(multibounce_F0(0.5), 0.5 * (1 + std::pow(0.5, 0.75) / 2));
  EXPECT_DOUBLE_EQ(multibounce_F1(0.5), 27.576937094210385 * 0.5 * std::pow(0.5, 1.5) *
                                            std::exp(-3.3364392003423804 * std::pow(0.5, 0.25)));
  EXPECT_EQ(multibounce_F0(0.0), 0.0);
  EXPECT_EQ(multibounce_F0(1.0), 1.0);
  EXPECT_EQ(multibounce_F1(0.0), 0.0);
  EXPECT_EQ(multibounce_F1(1.0), 0.0);
}

TEST(Multibounce, AoOneGivesOne) {
  for (float r : kAlbedos) {
    const Vec3 m = multibounce_ao(1.0f, {r, r, r});
    EXPECT_FLOAT_EQ(m.x, 1.0f) << r;
    EXPECT_FLOAT_EQ(multibounce_eq12(1.0f, {r, r, r}).x, 1.0f) << r;
  }
  // Clamped above 1.
  EXPECT_FLOAT_EQ(multibounce_ao(1.5f, {0.5f, 0.5f, 0.5f}).y, 1.0f);
}

TEST(Multibounce, AlbedoZeroGivesAo) {
  for (int i = 0; i <= 100; ++i) {
    const float ao = i / 100.0f;
    const Vec3 m = multibounce_ao(ao, {0, 0, 0});
    EXPECT_NEAR(m.x, ao, 1e-7) << ao;
    EXPECT_EQ(m.x, m.y);
    EXPECT_EQ(m.x, m.z);
  }
}

TEST(Multibounce, AlbedoOneConservesEnergy) {
  // The notes: with ρ = 1 "the sum of all bounces ... yields a constant return of energy",
  // E = E_0 for every AO value.
  for (int i = 0; i <= 100; ++i) {
    EXPECT_NEAR(multibounce_ao(i / 100.0f, {1, 1, 1}).x, 1.0f, 1e-6) << i;
    EXPECT_NEAR(multibounce_eq12(i / 100.0f, {1, 1, 1}).x, 1.0f, 1e-6) << i;
  }
}

TEST(Multibounce, MonotonicAndBounded) {
  for (int i = 0; i <= 200; ++i) {
    const float ao = i / 200.0f;
    float prev = -1.0f;
    for (int k = 0; k <= 100; ++k) {
      const float r = k / 100.0f;
      const float m = multibounce_ao(ao, {r, r, r}).x;
      EXPECT_GE(m, prev) << "ao " << ao << " albedo " << r;  // non-decreasing in albedo
      EXPECT_GE(m, ao - 1e-6f);
      EXPECT_LE(m, 1.0f + 1e-6f);
      prev = m;
    }
  }
  // Also non-decreasing in AO at fixed albedo.
  for (float r : kAlbedos) {
    float prev = -1.0f;
    for (int i = 0; i <= 1000; ++i) {
      const float m = multibounce_ao(i / 1000.0f, {r, r, r}).x;
      EXPECT_GE(m, prev - 1e-6f) << "albedo " << r << " ao " << i / 1000.0f;
      prev = m;
    }
  }
}

TEST(Multibounce, PerChannel) {
  const Vec3 m = multibounce_ao(0.4f, {0.2f, 0.5f, 0.9f});
  EXPECT_EQ(m.x, multibounce_ao(0.4f, {0.2f, 0.2f, 0.2f}).x);
  EXPECT_EQ(m.y, multibounce_ao(0.4f, {0.5f, 0.5f, 0.5f}).x);
  EXPECT_EQ(m.z, multibounce_ao(0.4f, {0.9f, 0.9f, 0.9f}).x);
  EXPECT_LT(m.x, m.y);
  EXPECT_LT(m.y, m.z);
}

TEST(Multibounce, AlphaFromAoInvertsF0) {
  const double a_max = multibounce_alpha_max();
  EXPECT_NEAR(a_max, 0.9492532351, 1e-9);
  EXPECT_NEAR(multibounce_F0(a_max), 1.0, 1e-12);
  for (int i = 0; i <= 1000; ++i) {
    const double ao = i / 1000.0;
    const double a = multibounce_alpha_from_ao(ao);
    EXPECT_GE(a, 0.0);
    EXPECT_LE(a, a_max);
    EXPECT_NEAR(multibounce_F0(a), ao, 1e-12) << ao;
  }
}

TEST(Multibounce, MatchesPrintedEq12WhereItIsRegular) {
  // For 0 < α < α_max (F0 < 1, no 0/0) the pole-free form is the printed eq. 12.
  for (int i = 1; i < 95; ++i) {
    const double alpha = i / 100.0;
    for (float r : kAlbedos) {
      const double want = printed_eq12(alpha, r);
      EXPECT_NEAR(multibounce_eq12(float(alpha), {r, r, r}).x, want, 2e-6) << alpha << " " << r;
      // multibounce_ao takes the cosine-weighted AO F0(α).
      EXPECT_NEAR(multibounce_ao(float(multibounce_F0(alpha)), {r, r, r}).x, want, 2e-6)
          << alpha << " " << r;
    }
  }
  // Spot values of the printed formula (computed by hand from eq. 7, 9, 11, 12):
  // α = 0.5: F0 = 0.648651, F1 = 0.294791, τ = 0.160973.
  EXPECT_NEAR(printed_eq12(0.5, 0.5), 0.648651 + 0.5 / (1 - 0.5 * 0.160973) * 0.294791, 2e-6);
  EXPECT_NEAR(multibounce_eq12(0.5f, {0.5f, 0.5f, 0.5f}).x, 0.808947, 2e-6);
}

TEST(Multibounce, PrintedEq12HasAPoleAboveAlphaMax) {
  // The discrepancy documented in multibounce.h: for α in (0.94925, 1), F0 > 1, τ > 1 and
  // the printed eq. 12 diverges at ρ = 1/τ.
  const double alpha = 0.97;
  EXPECT_GT(multibounce_F0(alpha), 1.0);
  const double tau = 1 - multibounce_F1(alpha) / (1 - multibounce_F0(alpha));
  EXPECT_NEAR(tau, 2.02196, 1e-5);
  const double pole = 1 / tau;                                 // ρ = 0.49457
  EXPECT_GT(printed_eq12(alpha, pole * (1 - 1e-5)), 100.0);    // just below the pole
  EXPECT_LT(printed_eq12(alpha, pole * (1 + 1e-5)), -100.0);   // just above it
  EXPECT_LT(printed_eq12(alpha, 0.6), multibounce_F0(alpha));  // bounce light subtracts
  EXPECT_NEAR(multibounce_F0(0.95), 1.000225, 1e-6);
  EXPECT_NEAR(1 / (1 - multibounce_F1(0.95) / (1 - multibounce_F0(0.95))), 0.020293, 1e-5);
  // Ours: F0 limited to 1, so E/E_0 = 1 there for every albedo.
  for (float r : kAlbedos) EXPECT_FLOAT_EQ(multibounce_eq12(float(alpha), {r, r, r}).x, 1.0f);
}

}  // namespace
}  // namespace hbil
