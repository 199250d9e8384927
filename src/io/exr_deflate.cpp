// exr_deflate.cpp: see exr_deflate.h.
#include "io/exr_deflate.h"

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfPartType.h>
#include <libdeflate.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <cstring>
#include <mutex>
#include <new>
#include <stdexcept>

#include "io/half_rows.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace hbil::io {

namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "OpenEXR stores samples little-endian; this reader copies them as they are");

// Where a wanted channel lies in one decoded scanline.
struct Plan {
  size_t offset;  // bytes from the start of the scanline (always even: samples are 2 or 4 B)
  Imf::PixelType type;
  const ExrChannelTarget* target;
};

// A block's bytes, either as stored or (ZIP) as the two halves the format interleaves: byte
// j of the scanline data is lo[j / 2] for even j and hi[j / 2] for odd j.
struct Bytes {
  const unsigned char* lo;
  const unsigned char* hi;
  bool split;
  uint32_t sample(size_t j, int size) const {  // the little-endian sample at byte j
    uint32_t v = 0;
    for (int k = 0; k < size; ++k) {
      const size_t at = j + size_t(k);
      const unsigned char byte = !split ? lo[at] : (at & 1) ? hi[at / 2] : lo[at / 2];
      v |= uint32_t(byte) << (8 * k);
    }
    return v;
  }
};

float to_float(uint32_t bits, Imf::PixelType type) {
  switch (type) {
    case Imf::HALF: {
      Imath::half h;
      h.setBits(uint16_t(bits));
      return float(h);
    }
    case Imf::FLOAT: {
      float f;
      std::memcpy(&f, &bits, 4);
      return f;
    }
    default:
      return float(bits);  // UINT, as OpenEXR converts it
  }
}

// Converts the wanted channels of the rows [row0, row0 + rows) of one block.
void convert(const Bytes& bytes, size_t line_bytes, size_t width, size_t row0, size_t rows,
             const std::vector<Plan>& plans) {
  for (size_t r = 0; r < rows; ++r)
    for (const Plan& p : plans) {
      const int size = p.type == Imf::HALF ? 2 : 4;
      const size_t j0 = r * line_bytes + p.offset;
      const size_t stride = p.target->stride;
      if (p.target->half) {  // a HALF channel kept as its bits
        std::uint16_t* bits = p.target->half + (row0 + r) * width * stride;
        if (bytes.split) {
          const unsigned char* lo = bytes.lo + j0 / 2;
          const unsigned char* hi = bytes.hi + j0 / 2;
          for (size_t x = 0; x < width; ++x) bits[x * stride] = std::uint16_t(lo[x] | hi[x] << 8);
        } else {
          for (size_t x = 0; x < width; ++x)
            bits[x * stride] = std::uint16_t(bytes.sample(j0 + x * 2, 2));
        }
        continue;
      }
      float* out = p.target->dst + (row0 + r) * width * stride;  // no float target when kept
      if (bytes.split && p.type == Imf::HALF) {                  // the common case, eight at a time
        split_halves_to_floats(bytes.lo + j0 / 2, bytes.hi + j0 / 2, width, out, stride);
      } else if (bytes.split) {
        // FLOAT or UINT: j0 is even, so sample x's four bytes are lo[2x], hi[2x], lo[2x + 1]
        // and hi[2x + 1] of the halves from j0 / 2 (Bytes::sample without its test a byte).
        const unsigned char* lo = bytes.lo + j0 / 2;
        const unsigned char* hi = bytes.hi + j0 / 2;
        auto word = [&](size_t x) {
          return uint32_t(lo[2 * x]) | uint32_t(hi[2 * x]) << 8 | uint32_t(lo[2 * x + 1]) << 16 |
                 uint32_t(hi[2 * x + 1]) << 24;
        };
        if (p.type == Imf::FLOAT) {
          for (size_t x = 0; x < width; ++x) {
            const uint32_t v = word(x);
            std::memcpy(out + x * stride, &v, 4);
          }
        } else {
          for (size_t x = 0; x < width; ++x) out[x * stride] = float(word(x));
        }
      } else {
        for (size_t x = 0; x < width; ++x)
          out[x * stride] = to_float(bytes.sample(j0 + x * size, size), p.type);
      }
    }
}

// Undoes ZIP's predictor: byte i was stored as t[i] - t[i - 1] + 128 (mod 256), so the data
// is the running sum of (stored - 128). With SSE2, 16 bytes at a time: a prefix sum within
// the register in four shifted adds, plus the running sum so far (carry); the carry grows by
// the register's own sum, taken from the prefix before the carry is added, so that one add a
// register is all that waits on the one before.
void undo_predictor(unsigned char* t, size_t n) {
  if (n == 0) return;
  size_t i = 1;
#ifdef __SSE2__
  __m128i carry = _mm_set1_epi8(char(t[0]));
  const __m128i bias = _mm_set1_epi8(char(0x80));
  for (; i + 16 <= n; i += 16) {
    __m128i v = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(t + i)), bias);
    v = _mm_add_epi8(v, _mm_slli_si128(v, 1));
    v = _mm_add_epi8(v, _mm_slli_si128(v, 2));
    v = _mm_add_epi8(v, _mm_slli_si128(v, 4));
    v = _mm_add_epi8(v, _mm_slli_si128(v, 8));
    __m128i sum = _mm_srli_epi16(v, 8);    // byte 15 (the register's sum), low byte of word 7
    sum = _mm_shufflehi_epi16(sum, 0xff);  // word 7 in all of the high half
    sum = _mm_unpackhi_epi64(sum, sum);    // and in the low half
    sum = _mm_or_si128(sum, _mm_slli_epi16(sum, 8));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(t + i), _mm_add_epi8(v, carry));
    carry = _mm_add_epi8(carry, sum);
  }
#endif
  for (; i < n; ++i) t[i] = (unsigned char)(t[i - 1] + t[i] - 128);
}

struct Inflater {
  libdeflate_decompressor* d = libdeflate_alloc_decompressor();
  Inflater() {
    if (!d) throw std::bad_alloc();
  }
  ~Inflater() { libdeflate_free_decompressor(d); }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;
};

}  // namespace

bool read_deflate_scanlines(Imf::InputFile& file, const std::vector<ExrChannelTarget>& targets) {
  const Imf::Header& header = file.header();
  if (header.hasTileDescription() || (header.hasType() && header.type() != Imf::SCANLINEIMAGE))
    return false;
  size_t block_rows;
  switch (header.compression()) {
    case Imf::ZIP_COMPRESSION:
      block_rows = 16;
      break;
    case Imf::ZIPS_COMPRESSION:
    case Imf::NO_COMPRESSION:
      block_rows = 1;
      break;
    default:
      return false;
  }
  const bool zipped = header.compression() != Imf::NO_COMPRESSION;
  const Imath::Box2i dw = header.dataWindow();
  const size_t width = size_t(int64_t(dw.max.x) - dw.min.x + 1);
  const size_t height = size_t(int64_t(dw.max.y) - dw.min.y + 1);

  std::vector<Plan> plans;
  size_t line_bytes = 0;
  for (auto c = header.channels().begin(); c != header.channels().end(); ++c) {
    const Imf::Channel& ch = c.channel();
    if (ch.xSampling != 1 || ch.ySampling != 1) return false;
    if (ch.type != Imf::HALF && ch.type != Imf::FLOAT && ch.type != Imf::UINT) return false;
    for (const ExrChannelTarget& t : targets)
      if (t.name == c.name()) {
        if (t.half && ch.type != Imf::HALF) return false;
        plans.push_back({line_bytes, ch.type, &t});
      }
    line_bytes += width * (ch.type == Imf::HALF ? 2 : 4);
  }
  if (plans.size() != targets.size()) return false;

  const size_t blocks = (height + block_rows - 1) / block_rows;
  std::mutex fetching;  // rawPixelData returns OpenEXR's own buffer: one block at a time
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, blocks, block_rows == 1 ? 16 : 1),
      [&](const tbb::blocked_range<size_t>& range) {
        // Per thread, kept from block to block and frame to frame: a block is a few MB at
        // 1920x1080, and fresh memory of that size costs page faults every time.
        thread_local Inflater inflater;
        thread_local std::vector<unsigned char> stored, inflated;
        for (size_t b = range.begin(); b != range.end(); ++b) {
          const size_t row0 = b * block_rows, rows = std::min(block_rows, height - row0);
          const int y0 = int(int64_t(dw.min.y) + int64_t(row0));
          const size_t expected = rows * line_bytes;
          {
            std::lock_guard<std::mutex> lock(fetching);
            const char* data;
            int size;
            file.rawPixelData(y0, data, size);
            stored.assign(data, data + size);
          }
          auto damaged = [&](const char* why) {
            return std::runtime_error("the block at rows " + std::to_string(y0) + "-" +
                                      std::to_string(y0 + int(rows) - 1) + " " + why);
          };
          Bytes bytes{stored.data(), nullptr, false};
          // A block that did not shrink is stored as it is (OpenEXR writes the smaller form).
          if (stored.size() != expected) {
            if (!zipped) throw damaged("has the wrong size");
            inflated.resize(expected);
            size_t got = 0;
            if (libdeflate_zlib_decompress(inflater.d, stored.data(), stored.size(),
                                           inflated.data(), expected, &got) != LIBDEFLATE_SUCCESS ||
                got != expected)
              throw damaged("is damaged: its ZIP data does not inflate to the block's size");
            unsigned char* t = inflated.data();
            undo_predictor(t, expected);
            bytes = Bytes{t, t + (expected + 1) / 2, true};
          }
          convert(bytes, line_bytes, width, row0, rows, plans);
        }
      });
  return true;
}

}  // namespace hbil::io
