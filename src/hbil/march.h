// march.h: marching the slices of pixels (the inner loop of the horizon search).
//
// march_horizon.cpp: two horizons per slice (HBIL §1.3, §2.1-2.2, eq. 16-18).
// march_bitmask.cpp: the visibility bitmask (Therrien et al. 2023) with measured or constant
//   thickness; the scalar reference.
// march_bitmask_simd.cpp: the same bitmask march for a run of pixels of one row, one pixel
//   per SIMD lane (Google Highway, the best instruction set chosen at run time). It gives the
//   scalar reference's results to the bit (tests/march_test.cpp).
// See horizon.h for the paper sections and every departure from them.
#pragma once

#include "hbil/horizon.h"

namespace hbil {

// Marches the slices at rotations phi[0..n) about ω_o (radians; φ = 0 is the slice holding
// the view-space x axis) for the pixel at texel (i, j) of `view`, with view-space position
// P and unit normal n. `fraction` holds the sample positions from step_fractions().
// Scalar; dispatches on c.bitmask.
PixelSums march_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                      const float* phi, int n_slices, const float* fraction,
                      const HorizonConfig& c);
PixelSums march_horizon_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                              const float* phi, int n_slices, const float* fraction,
                              const HorizonConfig& c);
PixelSums march_bitmask_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                              const float* phi, int n_slices, const float* fraction,
                              const HorizonConfig& c);

// The bitmask march of texels (i0 .. i0 + count − 1, j) of `view`, P and n read from the view
// itself; out[k] receives texel i0 + k's sums. Background texels (P.z >= the background)
// are left untouched.
void march_bitmask_row(const SampleView& view, int i0, int j, int count, const float* phi,
                       int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out);

}  // namespace hbil
