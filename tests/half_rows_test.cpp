// half_rows_test.cpp: the row conversions of io/half_rows.h give Imath's half results to the
// bit: every one of the 65536 halves to float (a NaN to a NaN), and floats of every exponent to
// half (ties, subnormals, the clamp at the largest half), contiguous and strided, of lengths that
// are and are not multiples of eight.
#include "io/half_rows.h"

#include <Imath/half.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace hbil::io {
namespace {

TEST(HalfRows, EveryHalfBecomesImathsFloat) {
  std::vector<unsigned char> lo(65536), hi(65536);
  for (size_t b = 0; b < 65536; ++b) {
    lo[b] = (unsigned char)(b & 0xff);
    hi[b] = (unsigned char)(b >> 8);
  }
  for (const size_t stride : {size_t(1), size_t(3)}) {
    std::vector<float> out(65536 * stride, -7.f);
    split_halves_to_floats(lo.data(), hi.data(), 65536, out.data(), stride);
    size_t differ = 0;
    for (size_t b = 0; b < 65536; ++b) {
      Imath::half h;
      h.setBits(std::uint16_t(b));
      const float want = float(h), got = out[b * stride];
      // A NaN stays a NaN (F16C quiets a signalling one); everything else to the bit.
      differ += std::isnan(want) ? !std::isnan(got) : std::memcmp(&want, &got, 4) != 0;
      if (stride == 3) EXPECT_EQ(out[b * stride + 1], -7.f);  // between the samples untouched
    }
    EXPECT_EQ(differ, 0u) << "stride " << stride;
  }
  // A length that is not a multiple of eight ends one at a time.
  std::vector<float> out(13, -7.f);
  split_halves_to_floats(lo.data() + 0x3c00, hi.data() + 0x3c00, 13, out.data(), 1);
  EXPECT_EQ(out[0], 1.f);
  Imath::half last;
  last.setBits(0x3c0c);
  EXPECT_EQ(out[12], float(last));
}

TEST(HalfRows, FloatsBecomeImathsNearestHalf) {
  // Every 65537th float bit pattern that is finite, plus the cases rounding turns on.
  std::vector<float> in;
  for (std::uint64_t b = 0; b < (std::uint64_t(1) << 32); b += 65537) {
    float f;
    const std::uint32_t bits = std::uint32_t(b);
    std::memcpy(&f, &bits, 4);
    if (std::isfinite(f)) in.push_back(f);
  }
  for (const float f : {0.f, -0.f, 1.f, 1.f + 1.f / 2048, 1.f + 3.f / 2048, 65504.f, 65519.f,
                        65520.f, 1e9f, -1e9f, 5.96e-8f, 2.98e-8f, 8.9e-8f, 6.1e-5f, 1e-30f})
    in.push_back(f);
  for (const size_t stride : {size_t(1), size_t(3)}) {
    std::vector<float> strided(in.size() * stride, 0.f);
    for (size_t k = 0; k < in.size(); ++k) strided[k * stride] = in[k];
    for (const size_t n : {in.size(), size_t(7), size_t(9)}) {
      std::vector<std::uint16_t> out(n);
      floats_to_half_bits(strided.data(), stride, n, out.data());
      size_t differ = 0;
      for (size_t k = 0; k < n; ++k) {
        const float v = std::fmin(std::fmax(in[k], -65504.f), 65504.f);
        differ += out[k] != Imath::half(v).bits();
      }
      EXPECT_EQ(differ, 0u) << "stride " << stride << ", " << n << " values";
    }
  }
  // Beyond the largest half: the largest half, not an infinity.
  std::uint16_t big[9];
  const float huge[9] = {1e9f, -1e9f, 70000.f, 3e38f, 1, 2, 3, 4, 5};
  EXPECT_TRUE(floats_to_half_bits(huge, 1, 9, big));
  EXPECT_EQ(big[0], 0x7bffu);
  EXPECT_EQ(big[1], 0xfbffu);
  EXPECT_EQ(big[2], 0x7bffu);
  EXPECT_EQ(big[3], 0x7bffu);
}

TEST(HalfRows, AnInfinityOrANaNIsReported) {
  std::vector<float> v(20, 0.5f);
  std::vector<std::uint16_t> out(20);
  EXPECT_TRUE(floats_to_half_bits(v.data(), 1, 20, out.data()));
  for (const size_t at : {size_t(2), size_t(17)})  // in a group of eight, and in the tail
    for (const float bad : {INFINITY, -INFINITY, NAN}) {
      std::vector<float> w = v;
      w[at] = bad;
      EXPECT_FALSE(floats_to_half_bits(w.data(), 1, 20, out.data())) << bad << " at " << at;
    }
}

}  // namespace
}  // namespace hbil::io
