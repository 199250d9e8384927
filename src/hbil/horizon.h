// horizon.h: the horizon search of one pixel and the closed-form slice integrals (the
// marches themselves are in march.h).
//
// Implements HBIL (Mayaux 2018) §1.3 (horizon angles measured from the local view vector),
// §2.1 (horizons initialised from the normal), §2.2.1 (bent normal, eq. 4-6) and §2.2.2
// (cosine-weighted AO, eq. 9-11, after GTAO, Jimenez et al. 2016).
//
// Slice space: θ is measured from the view vector ω_o (θ = 0 points at the camera), positive
// towards the slice direction D. A slice is visible between the back horizon θ0 <= 0 and the
// front horizon θ1 >= 0; in the slice parametrisation of the hemisphere dω = |sin θ| dθ dφ,
// φ in [0, π).
//
// Departures from the paper, with reasons:
//  - Eq. 5 and eq. 11 as printed integrate sin θ, not |sin θ|, over [θ0, θ1]; with θ0 < 0 that
//    gives a non-zero tangential bent normal and an AO != 1 for an unoccluded view-facing
//    plane. We integrate with |sin θ| (the Jacobian eq. 4 and eq. 10 state), as GTAO does:
//    ∫_{θ0}^{θ1} f(θ)|sin θ| dθ = G(θ1) − G(θ0) with G(θ) = sgn(θ) ∫_0^{|θ|}... in closed form.
//  - §1.3 corrects a screen-space angle β by the angle α between camera axis and view vector.
//    We compute the same θ directly as acos(ω_o · (x' − x)/|x' − x|) from view-space
//    positions: for a pinhole camera every sample along the screen line lies in the slice
//    plane (the plane through the eye, the pixel's ray and the line), so this is exact and
//    also valid for off-axis pixels and non-square pixels.
//  - Samples are fetched at whole texels, up to half a texel off the slice's screen line, so
//    their view-space points leave the slice plane; on a slanted plane a point beside the
//    line can lie above the in-slice tangent and reads as an occluder (up to 0.13 of AO lost
//    on an unoccluded oblique floor). Each sample is therefore moved along its own tangent
//    plane onto the ray through the exact position on the line: exact for planes, second
//    order for curved surfaces; skipped where that ray grazes the sample's surface.
//  - Slices are spaced evenly in their rotation φ about ω_o, which the measure
//    dω = |sin θ| dθ dφ requires, and each slice's screen line is derived from it. Spacing
//    them evenly in screen angle (HBAO, XeGTAO) is the same only at the image centre; off
//    centre it biases AO (0.02 on an unoccluded oblique floor with 32 slices).
//  - Bitmask thickness from back faces (Therrien et al. use one constant): where the input
//    has a back-face depth, a sample occludes along its ray as far as its object really
//    extends. That thickness is honest, unlike the constant (tuned on point samples to also
//    stand for the surface between samples), so such a sample is not a point: it covers its
//    tangent plane between the rays half way to its neighbours on the line, extruded by the
//    thickness. Without that, light leaks between the samples of a 10 cm wall.
//  - The cone aperture (eq. 12) uses the uniform (solid-angle) visibility Ω/2π, the quantity
//    eq. 12 is derived from, not the cosine-weighted AO: cos α = 1 − Ω/2π.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hbil/camera.h"
#include "hbil/params.h"
#include "hbil/vecmath.h"

namespace hbil {

// Per-frame constants of the march, made once from Params and Camera.
struct HorizonConfig {
  float radius = 1;      // world units
  int steps = 12;        // per side
  float step_power = 2;  // sample spacing exponent
  float fx = 1, fy = 1;  // full-resolution focal lengths, pixels
  bool bitmask = false;  // visibility bitmask (Therrien et al. 2023) instead of two horizons
  float thickness = 0.4f, thickness_growth = 0;  // bitmask occluder thickness: t + growth * z
  float gather_thickness = 0.4f;  // the same t for the gather-only samples (beyond `steps`)
  float gather_radius = 1;        // world units, >= radius: how far the irradiance gather reaches
  int gather_steps = 0;           // samples per side between radius and gather_radius (gather only)
  // Radiance assumed in the directions where the gather finds nothing: no sample within
  // gather_radius, or the screen edge first (the bitmask's sectors the gather left open, the
  // band between the horizon march's two gather horizons). Zero: those directions send nothing.
  Vec3 fill;
  bool has_fill() const { return fill.x != 0.f || fill.y != 0.f || fill.z != 0.f; }
  // The same per pixel (indexed like the searched ViewGBuffer), or null: `fill` everywhere.
  // The radiance cache's estimate of what each pixel's unseen directions see (cache.h).
  const Vec3* fill_map = nullptr;
  // Temporal chain (HBIL §3.3 with accumulation): every slice angle turns by `rotation`
  // (radians) and every step jitter shifts by `jitter_shift` (mod 1), both from the frame.
  float rotation = 0, jitter_shift = 0;
  bool vectorised = true;  // march_row (SIMD, either method) instead of march_pixel
};
// The rotation and jitter shift of frame `frame` for `directions` evenly spaced slice
// directions per block: a van der Corput fraction of the spacing π/directions, and the
// golden-ratio sequence, so that successive frames fill in between each other's directions.
void frame_rotation(int frame, int directions, float& rotation, float& jitter_shift);
HorizonConfig make_horizon_config(const Params& p, const Camera& cam);

// The integrals of one slice between θ0 <= θ1 for a normal whose projection onto the slice
// plane is (nx, ny) = (n·D, n·ω_o):
//   ao  = ∫ (n'·ω'(θ)) |sin θ| dθ           (eq. 10; 1 for a view-facing, unoccluded slice)
//   vis = ∫ |sin θ| dθ                      (solid angle of the slice; 2 when unoccluded)
//   bx, by = ∫ (sin θ, cos θ) |sin θ| dθ    (eq. 4-6, slice-space bent vector)
struct SliceTerms {
  float ao = 0, vis = 0, bx = 0, by = 0;
};
SliceTerms integrate_slice(float theta0, float theta1, float nx, float ny);

// A read-only, possibly strided, view of view-space positions and unit normals: texel (i, j)
// is element j * row + i * col. A deinterleaved sub-buffer is contiguous (col = 1); the same
// sub-buffer read in place from the full-resolution image has col = 4, row = 4 * width.
struct SampleView {
  const Vec3* position = nullptr;
  const Vec3* normal = nullptr;
  int width = 0, height = 0;
  std::ptrdiff_t col = 1, row = 0;
  int stride = 1;                  // full-resolution pixels per texel (4 when deinterleaved)
  const Vec3* radiance = nullptr;  // source radiance L_d (eq. 16); null: no gathering
  // Bitmask occluder thickness along the view ray per texel (from back faces); null or a
  // negative value: the constant of HorizonConfig.
  const float* thickness = nullptr;
  // HorizonConfig::fill per texel (from its fill_map), or null: HorizonConfig::fill.
  const Vec3* fill = nullptr;
  // Per texel, indexed like them, two 8-byte words (texel_surfaces), or null: the bits of
  // the normal's (x, y) and of (z, dot(position, normal)), each word's first float in its
  // low 32 bits. The SIMD marches load a sample's word pair with two 8-byte gathers, and move
  // a sample onto the slice's ray along its tangent plane (march_common.h's take_step) with
  // them, so that they gather a texel's position only where that move does not apply (a
  // grazing ray): the same bits, fewer loads.
  const std::uint64_t* surface = nullptr;
  std::ptrdiff_t index(int i, int j) const { return j * row + i * col; }
  // Whether a gathering march lights its empty directions, and with what at texel (i, j).
  bool fills(const HorizonConfig& c) const { return radiance && (fill || c.has_fill()); }
  Vec3 fill_at(const HorizonConfig& c, int i, int j) const {
    return fill ? fill[index(i, j)] : c.fill;
  }
};

// SampleView::surface of `count` contiguous texels: normal[k] and dot(position[k], normal[k]).
std::vector<std::uint64_t> texel_surfaces(const Vec3* position, const Vec3* normal, size_t count);

// Sums over the slices of one pixel (means are taken by the caller).
struct PixelSums {
  float ao = 0;     // Σ ao_i
  float vis = 0;    // Σ vis_i
  Vec3 bent;        // Σ (D_i bx_i + ω_o by_i), view space
  Vec3 irradiance;  // Σ over slices of Σ_bands L_d(x') ΔI (eq. 18): mean = E_near / π
};

// Sample positions along a slice: ((k + jitter)/steps)^power for k < steps, as fractions of
// the AO radius, then (k + jitter)/gather_steps for the gather-only samples, as fractions of
// the way from the AO radius to the gather radius. The same for every pixel of a sub-buffer,
// so it is made once.
std::vector<float> step_fractions(const HorizonConfig& c, float jitter);

}  // namespace hbil
