// march.h: marching the slices of pixels (the inner loop of the horizon search).
//
// march_horizon.cpp: two horizons per slice (HBIL §1.3, §2.1-2.2, eq. 16-18).
// march_bitmask.cpp: the visibility bitmask (Therrien et al. 2023) with measured or constant
//   thickness; the scalar reference.
// march_bitmask_simd.cpp, march_horizon_simd.cpp: the same marches for a run of pixels of one
//   row, one pixel per SIMD lane (Google Highway, the best instruction set chosen at run
//   time; what they share is in march_simd-inl.h). They give the scalar references' results
//   to the bit (tests/march_test.cpp).
// See horizon.h for the paper sections and every departure from them.
#pragma once

#include <cstdint>
#include <vector>

#include "hbil/horizon.h"

namespace hbil {

// The light a bitmask march gathered, sample by sample, so that a later in-frame bounce (the
// same geometry, another source radiance) is summed again without marching: per pixel of a
// run and per slice, the samples whose sectors were newly covered, in march order, with their
// rejection-filter weight fw (§3.4) and sector weight w (eq. 18). Summing
// Σ_slices Σ_entries (L[src] · fw) · w in this order gives the march's irradiance to the bit.
struct GatherEntry {
  std::uint32_t src;  // the sample's index in the view (SampleView::index), or kFillSource
  float fw, w;
  // The entry of a slice's open sectors (w: their weight), lit by HorizonConfig::fill.
  static constexpr std::uint32_t kFillSource = 0xFFFFFFFFu;
};
struct GatherLog {
  std::vector<GatherEntry> entries;   // pixel by pixel, slice by slice
  std::vector<std::uint16_t> counts;  // entries per pixel and slice (n_slices per pixel)
};

// Marches the slices at rotations phi[0..n) about ω_o (radians; φ = 0 is the slice holding
// the view-space x axis) for the pixel at texel (i, j) of `view`, with view-space position
// P and unit normal n. `fraction` holds the sample positions from step_fractions().
// Scalar; dispatches on c.bitmask. `log`: see march_bitmask_pixel (the horizon method
// logs nothing).
PixelSums march_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                      const float* phi, int n_slices, const float* fraction, const HorizonConfig& c,
                      GatherLog* log = nullptr);
PixelSums march_horizon_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                              const float* phi, int n_slices, const float* fraction,
                              const HorizonConfig& c);
// `log` (optional, with a radiance source): appends this pixel's gather (see GatherLog).
PixelSums march_bitmask_pixel(const SampleView& view, int i, int j, const Vec3& P, const Vec3& n,
                              const float* phi, int n_slices, const float* fraction,
                              const HorizonConfig& c, GatherLog* log = nullptr);

// The bitmask march of texels (i0 .. i0 + count − 1, j) of `view`, P and n read from the view
// itself; out[k] receives texel i0 + k's sums. Background texels (P.z >= the background)
// are left untouched (and log nothing). `log`: as march_bitmask_pixel, texel by texel.
void march_bitmask_row(const SampleView& view, int i0, int j, int count, const float* phi,
                       int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out,
                       GatherLog* log = nullptr);

// The horizon march of texels (i0 .. i0 + count − 1, j), as march_bitmask_row (no log).
void march_horizon_row(const SampleView& view, int i0, int j, int count, const float* phi,
                       int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out);
// The row march of c's method; `log` is used by the bitmask only.
inline void march_row(const SampleView& view, int i0, int j, int count, const float* phi,
                      int n_slices, const float* fraction, const HorizonConfig& c, PixelSums* out,
                      GatherLog* log = nullptr) {
  if (c.bitmask)
    march_bitmask_row(view, i0, j, count, phi, n_slices, fraction, c, out, log);
  else
    march_horizon_row(view, i0, j, count, phi, n_slices, fraction, c, out);
}
// The instruction set the row marches run with on this machine ("AVX3" = AVX-512,
// "AVX2", "SSE4", ...): the best one the processor supports, chosen at run time. Every one
// gives the same results to the bit.
const char* march_simd_target();

// The irradiance sum of one logged pixel with source radiance `radiance` (indexed like the
// view the log was made on) and `fill` in its open directions (HorizonConfig::fill); `entry`
// and `count` advance past it.
Vec3 replay_gather(const GatherLog& log, const Vec3* radiance, const Vec3& fill, int n_slices,
                   size_t& entry, size_t& count);

}  // namespace hbil
