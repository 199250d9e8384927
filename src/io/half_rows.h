// half_rows.h: rows of half floats to floats and back, eight at a time with the processor's
// F16C instructions where it has them (checked once at run time), else one at a time through
// Imath. Both give Imath's results to the bit: every half is a float exactly, and a float
// becomes the nearest half, ties to even, as Imath's half(float) rounds. (Only a signalling
// NaN half differs: F16C makes it a quiet NaN, Imath keeps its bits; a NaN either way.)
#pragma once

#include <cstddef>
#include <cstdint>

namespace hbil::io {

// The n halves whose low bytes are lo[0..n) and high bytes hi[0..n) (as ZIP's split stores
// them), as floats at out[k * stride].
void split_halves_to_floats(const unsigned char* lo, const unsigned char* hi, size_t n, float* out,
                            size_t stride);

// The bits of the halves nearest in[k * stride], k < n, each first clamped to ±65504 (the
// largest finite half). False when a value is not finite (an infinity or a NaN), whose half
// is then not defined.
bool floats_to_half_bits(const float* in, size_t stride, size_t n, std::uint16_t* out);

}  // namespace hbil::io
