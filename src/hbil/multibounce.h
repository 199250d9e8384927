// multibounce.h: multi-bounce ambient occlusion, after Mayaux, "Improved Ambient Occlusion"
// (study notes; /work/shared/papers/improved-ambient-occlusion-multibounce.md).
//
// What it approximates. For a Lambertian surface of albedo ρ under a distant, uniform
// radiance, the irradiance that reaches a point x through its unoccluded directions plus all
// the light that bounces between x's occluding neighbours (assumed to share x's albedo and
// AO) before arriving, as a fraction of the unoccluded irradiance E_0 (eq. 8):
//   E/E_0 = F0(α) + ρ F1(α) + ρ² F2(α) + ...,
// where α is the AO and F_i the fraction after i bounces, fitted on height-field renders.
// Assuming F_{i+1} = τ F_i and energy conservation at ρ = 1 (Σ F_i = 1) gives eq. 9 and 12:
//   E/E_0 = F0(α) + ρ/(1 − ρτ) · F1(α)                                            (eq. 12)
//   F0(α) = α (1 + (1 − α)^0.75 / 2)                                               (eq. 7)
//   F1(α) = A α (1 − α)^1.5 exp(−B α^(1/4)),  A = 27.576937094210385,
//                                             B = 3.3364392003423804            (eq. 11)
//   τ     = 1 − F1(α) / (1 − F0(α))                                                (eq. 9)
// evaluated per RGB channel of ρ (the paper insists on it: colour saturation of bounces).
//
// Which AO: the paper's α is the solid-angle visibility (1/2π) ∫ V dω (its eq. 4, measured
// by counting unoccluded rays), and F0 (eq. 6-7) is its fit of the cosine-weighted visibility
// (1/π) ∫ V (n·ω) dω as a function of α. hbil's AO is the cosine-weighted one (horizon.h,
// HBIL eq. 9), i.e. already F0(α). multibounce_ao therefore takes the cosine-weighted AO and
// finds the α with F0(α) = ao: the direct term is then exactly ao (albedo 0 gives ao back)
// and F1, τ are evaluated where the fit places that visibility. multibounce_eq12 takes α.
//
// Discrepancies found in the paper, and what we do:
//  - F0 exceeds 1 for α in (0.94925, 1) (maximum 1.00614 at α ≈ 0.983). There 1 − F0 < 0,
//    τ > 1, and eq. 12's factor ρ/(1 − ρτ) has a pole at ρ = 1/τ inside [0, 1]: e.g. at
//    α = 0.97, τ = 2.02, eq. 12 diverges at ρ = 0.495 and is negative above it; at α = 0.95,
//    at ρ = 0.0203. We limit F0 to 1 (no occlusion cannot return more than the unoccluded
//    irradiance), so the bounce term vanishes there and E/E_0 = 1.
//  - τ is 0/0 at α = 1 (F1 = 0, F0 = 1) and ρ/(1 − ρτ) F1 is ∞·0 at α = 0 with ρ = 1. We
//    evaluate the algebraically identical, pole-free form (a = 1 − F0 >= 0, b = F1 >= 0)
//        ρ/(1 − ρτ) F1 = ρ a b / ((1 − ρ) a + ρ b),
//    which is non-decreasing in ρ, equals a = 1 − F0 at ρ = 1 (E/E_0 = 1: the paper's
//    energy conservation) and 0 at ρ = 0. Where it is 0/0 we take its limit along α:
//    a at ρ = 1, else 0.
//  - τ is negative for α in (0.7633, 0.94925) (F1 > 1 − F0: the fitted first bounce
//    already exceeds the energy left). This is no pole (1 − ρτ > 1) and is kept as printed.
// The paper gives no table of reference values; its stated property is E/E_0 = 1 at ρ = 1
// for every α, which the tests check.
//
// Inputs are clamped: ao and α to [0, 1], each albedo channel to [0, 1].
#pragma once

#include "hbil/vecmath.h"

namespace hbil {

// The fitted constants of eq. 11, as printed.
inline constexpr double kMultibounceA = 27.576937094210385;
inline constexpr double kMultibounceB = 3.3364392003423804;

double multibounce_F0(double alpha);  // eq. 7, as printed (not limited to 1)
double multibounce_F1(double alpha);  // eq. 11
// The α in (0.9, 1) where F0(α) = 1 (0.949253...); F0 < 1 below it.
double multibounce_alpha_max();

// Eq. 12 divided by E_0, for the solid-angle AO α (hbil: 1 − bentcone.W), with F0 limited
// to 1 and the pole-free form above. Per channel of `albedo`; in [F0(α), 1].
Vec3 multibounce_eq12(float alpha, Vec3 albedo);

// Multi-bounce AO for hbil's cosine-weighted AO: eq. 12 / E_0 at the α with F0(α) = ao
// (α in [0, multibounce_alpha_max()]). 1 at ao = 1 for any albedo, ao at albedo 0, 1 at
// albedo 1, non-decreasing in each albedo channel; in [ao, 1].
Vec3 multibounce_ao(float ao, Vec3 albedo);

// The α with F0(α) = ao, ao clamped to [0, 1] (ao >= 1 gives multibounce_alpha_max()).
double multibounce_alpha_from_ao(double ao);

}  // namespace hbil
