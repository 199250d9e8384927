// half_rows.cpp: see half_rows.h.
#include "io/half_rows.h"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#include <immintrin.h>
#define HBIL_HALF_ROWS_X86 1
#endif

namespace hbil::io {

namespace {

constexpr float kHalfMax = 65504.f;

void split_scalar(const unsigned char* lo, const unsigned char* hi, size_t n, float* out,
                  size_t stride) {
  for (size_t k = 0; k < n; ++k) {
    Imath::half h;
    h.setBits(std::uint16_t(lo[k] | hi[k] << 8));
    out[k * stride] = float(h);
  }
}

bool to_half_scalar(const float* in, size_t stride, size_t n, std::uint16_t* out) {
  bool finite = true;
  for (size_t k = 0; k < n; ++k) {
    const float v = in[k * stride];
    const bool ok = std::isfinite(v);
    finite &= ok;
    out[k] = ok ? Imath::half(std::clamp(v, -kHalfMax, kHalfMax)).bits() : 0;
  }
  return finite;
}

#ifdef HBIL_HALF_ROWS_X86
// CPUID leaf 1: F16C (ECX bit 29) and AVX (bit 28), and OSXSAVE (bit 27) with the system
// saving the AVX registers (XCR0 bits 1 and 2). (Not __builtin_cpu_supports: Clang 14 does
// not know "f16c".)
bool has_f16c() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(1, &a, &b, &c, &d)) return false;
  constexpr unsigned kNeed = (1u << 27) | (1u << 28) | (1u << 29);
  if ((c & kNeed) != kNeed) return false;
  unsigned lo = 0, hi = 0;
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
  return (lo & 6u) == 6u;
}

__attribute__((target("avx,f16c"))) void split_f16c(const unsigned char* lo,
                                                    const unsigned char* hi, size_t n, float* out,
                                                    size_t stride) {
  size_t k = 0;
  alignas(32) float tmp[8];
  for (; k + 8 <= n; k += 8) {
    const __m128i l = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(lo + k));
    const __m128i h = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(hi + k));
    const __m256 f = _mm256_cvtph_ps(_mm_unpacklo_epi8(l, h));
    if (stride == 1) {
      _mm256_storeu_ps(out + k, f);
    } else {
      _mm256_store_ps(tmp, f);
      for (size_t j = 0; j < 8; ++j) out[(k + j) * stride] = tmp[j];
    }
  }
  split_scalar(lo + k, hi + k, n - k, out + k * stride, stride);
}

__attribute__((target("avx,f16c"))) bool to_half_f16c(const float* in, size_t stride, size_t n,
                                                      std::uint16_t* out) {
  size_t k = 0;
  alignas(32) float tmp[8];
  const __m256 lo = _mm256_set1_ps(-kHalfMax), hi = _mm256_set1_ps(kHalfMax);
  __m256 bad = _mm256_setzero_ps();  // x − x: 0 for a finite x, NaN for an infinity or a NaN
  for (; k + 8 <= n; k += 8) {
    __m256 f;
    if (stride == 1) {
      f = _mm256_loadu_ps(in + k);
    } else {
      for (size_t j = 0; j < 8; ++j) tmp[j] = in[(k + j) * stride];
      f = _mm256_load_ps(tmp);
    }
    bad = _mm256_or_ps(bad, _mm256_cmp_ps(_mm256_sub_ps(f, f), f, _CMP_UNORD_Q));
    f = _mm256_min_ps(_mm256_max_ps(f, lo), hi);
    const __m128i h = _mm256_cvtps_ph(f, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + k), h);
  }
  const bool tail = to_half_scalar(in + k * stride, stride, n - k, out + k);
  return tail && _mm256_movemask_ps(bad) == 0;
}
#else
bool has_f16c() {
  return false;
}
#endif

const bool kVectorised = has_f16c();

}  // namespace

void split_halves_to_floats(const unsigned char* lo, const unsigned char* hi, size_t n, float* out,
                            size_t stride) {
#ifdef HBIL_HALF_ROWS_X86
  if (kVectorised) return split_f16c(lo, hi, n, out, stride);
#endif
  split_scalar(lo, hi, n, out, stride);
}

bool floats_to_half_bits(const float* in, size_t stride, size_t n, std::uint16_t* out) {
#ifdef HBIL_HALF_ROWS_X86
  if (kVectorised) return to_half_f16c(in, stride, n, out);
#endif
  return to_half_scalar(in, stride, n, out);
}

}  // namespace hbil::io
