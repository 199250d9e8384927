// farfield.h: far-field (distant environment) irradiance through a bent cone, from an
// order-2 spherical-harmonic (SH) encoding of the environment's radiance.
//
// Implements HBIL (Mayaux 2018) §2.2.4: the irradiance estimate of Ramamoorthi & Hanrahan
// 2001 ("An Efficient Representation for Irradiance Environment Maps", eq. 12-13), with the
// upper bound of the clamped-cosine integral π/2 replaced by the cone half-angle θmax:
//   A_l(t) = 2π ∫_0^θmax Y_l0(θ) cos θ sin θ dθ,   t = cos θmax.
// hbil's bent cone gives t directly: t = bentcone.W = cos α = 1 − Ω/2π (horizon.h), i.e. the
// paper's t = 1 − AO with AO the solid-angle visibility.
//
// Check of the paper's coefficients (derivation in farfield.cpp): with μ = cos θ,
//   A_0 = (√π/2)(1 − t²),  A_1 = (√(3π)/3)(1 − t³),  A_2 = (√(5π)/8)·[3(1 − t⁴) − 2(1 − t²)],
// and E(n) = Σ_l √(4π/(2l+1)) A_l Σ_m L_lm Y_lm(n). Writing that out with the basis below
// gives exactly the paper's printed form, with c0 = A_0, c1 = A_1 and c2 = A_2/2 (the 1/2
// is Y_20's and Y_22's normalisation folded into c2): the paper's c0, c1, c2 are right. At
// t = 0 they give R&H's Â_0 = π, Â_1 = 2π/3, Â_2 = π/4. No discrepancy was found.
//
// Conventions:
//  - Directions are world space, Blender's: right-handed, Z up.
//  - SH basis: real, orthonormal over the sphere (∫ Y_i Y_j dω = δ_ij), R&H 2001 eq. 3,
//    index k = l(l+1) + m, for a unit direction (x, y, z):
//      k=0 (0, 0)  Y = 0.282095                = 1/(2√π)
//      k=1 (1,-1)  Y = 0.488603 y              = √(3/4π) y
//      k=2 (1, 0)  Y = 0.488603 z
//      k=3 (1, 1)  Y = 0.488603 x
//      k=4 (2,-2)  Y = 1.092548 xy             = √(15/4π) xy
//      k=5 (2,-1)  Y = 1.092548 yz
//      k=6 (2, 0)  Y = 0.315392 (3z² − 1)      = √(5/16π) (3z² − 1)
//      k=7 (2, 1)  Y = 1.092548 xz
//      k=8 (2, 2)  Y = 0.546274 (x² − y²)      = √(15/16π) (x² − y²)
//    Coefficients are L_lm = ∫ L(ω) Y_lm(ω) dω of the radiance L, so a constant radiance L
//    has L_00 = 2√π L and all others zero.
//  - Equirectangular images follow Blender's Environment Texture node (Cycles
//    kernel/camera/projection.h direction_to_equirectangular, range (−2π, π, −π, π); EEVEE
//    node_tex_environment_equirectangular):
//      u = 0.5 − atan2(y, x)/(2π),   v = 0.5 + atan2(z, hypot(x, y))/π   (v up),
//    so the image centre (u = 0.5) looks along +X, u = 0.25 along +Y, u = 0.75 along −Y,
//    and the top row (v = 1) is the zenith +Z. Blender stores images bottom row first; image
//    files (and OIIO) are top row first, so pixel (i, j) of a w × h file, row j counted
//    from the top, has its centre at u = (i + 0.5)/w, v = 1 − (j + 0.5)/h.
//    Note: the form u = atan2(y, −x)/(2π) + 0.5 is NOT Blender's: it is rotated 180° about Z
//    (it sends +X to the image edge u = 0/1); Blender's is −atan2(y, x)/(2π) + 0.5.
//  - Irradiance E is in the radiance's unit times steradians (W/m² for radiance in
//    W/(m²·sr)): a constant radiance L gives E = π L over the hemisphere (t = 0) and
//    E = π L sin²θmax = π L (1 − t²) over a cone. Outgoing diffuse radiance is ρ E / π.
//
// Departures, with reasons:
//  - cone_irradiance clamps t to [0, 1]: a cone wider than the hemisphere (t < 0) would count
//    directions below the surface with a negative cosine.
//  - Its result is clamped to >= 0 per channel: an order-2 reconstruction rings negative
//    opposite strong, small light sources; irradiance cannot be negative.
//  - project_equirect does not sample the basis at pixel centres with a cos(latitude)
//    weight; it projects the image's box reconstruction exactly (each pixel constant over
//    its latitude-longitude rectangle, the basis integrated over it in closed form). The
//    weights then sum to 4π exactly and a constant image has L_00 = 2√π L and all other
//    coefficients 0 (to rounding) at any resolution; the midpoint rule errs by O(1/h²)
//    (centre values with exact pixel solid angles leave L_20 = 1.8e-3 L_00 on a
//    constant 64 x 32 image). For smooth images both are O(1/h²).
#pragma once

#include "hbil/vecmath.h"

namespace hbil {

// RGB order-2 SH coefficients of a radiance function, index k = l(l+1) + m (see above).
struct SH9 {
  Vec3 c[9];
};

// The 9 basis functions at a unit direction, in the order above.
void sh9_basis(const Vec3d& dir, double Y[9]);

// Blender's equirectangular mapping (see above). (u, v) in [0, 1]², v up.
Vec3d equirect_to_direction(double u, double v);
void direction_to_equirect(const Vec3d& dir, double& u, double& v);

// Projects an equirectangular radiance image onto SH9 (exactly, for the image taken as
// constant over each pixel). `rgb` holds width × height pixels of 3 floats (R, G, B),
// row-major, top row first. Deterministic: rows are summed in order
// whatever the thread count. Throws Error(Exit::bad_data) when width or height is < 1 or a
// value is not finite (naming the pixel and the value).
SH9 project_equirect(const float* rgb, int width, int height);

// The SH9 of a constant radiance L: L_00 = 2√π L, the rest zero.
SH9 constant_environment(Vec3 L);

// Irradiance from the directions within θmax of the unit vector n (HBIL §2.2.4):
//   E(n) = ∫_{ω·n >= cos θmax} L(ω) (n·ω) dω,  with L the order-2 SH reconstruction,
// evaluated as c0 L00 + c1 (y L1-1 + z L10 + x L11) + c2 L20 (3z² − 1)
//   + c2 √3 L22 (x² − y²) + 2√3 c2 (xy L2-2 + yz L2-1 + xz L21),   t = cos θmax.
// t = 0 is the whole hemisphere (R&H 2001). t is clamped to [0, 1], E to >= 0.
Vec3 cone_irradiance(const SH9& L, Vec3 n, float cos_theta_max);

// The paper's c0, c1, c2 at t = cos θmax (t clamped to [0, 1]).
void cone_sh_coefficients(float t, float& c0, float& c1, float& c2);

}  // namespace hbil
