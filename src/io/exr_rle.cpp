// exr_rle.cpp: see exr_rle.h.
#include "io/exr_rle.h"

#include <algorithm>
#include <bit>
#include <cstring>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace hbil::io {

namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "EXR files are little-endian; this writer copies integers as they are");

// The longest run (a count byte of 127: 128 bytes) and the longest literal (127 bytes).
constexpr size_t kMaxRun = 128, kMaxLiteral = 127;

// The end of the run of in[i] that starts at i: the first j in (i, min(n, i + kMaxRun)) with
// in[j] != in[i], or that limit.
size_t run_end(const unsigned char* in, size_t n, size_t i) {
  const size_t limit = std::min(n, i + kMaxRun);
  size_t j = i + 1;
#ifdef __SSE2__
  const __m128i v = _mm_set1_epi8(char(in[i]));
  for (; j + 16 <= limit; j += 16) {
    const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + j));
    const unsigned differ = ~unsigned(_mm_movemask_epi8(_mm_cmpeq_epi8(x, v))) & 0xffffu;
    if (differ) return j + size_t(std::countr_zero(differ));
  }
#endif
  for (; j < limit; ++j)
    if (in[j] != in[i]) return j;
  return limit;
}

// The first j in [from, limit) where three equal bytes start (in[j] == in[j+1] == in[j+2],
// j + 2 < n), or limit.
size_t triple_start(const unsigned char* in, size_t n, size_t from, size_t limit) {
  size_t j = from;
#ifdef __SSE2__
  for (; j + 18 <= n && j + 16 <= limit; j += 16) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + j));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + j + 1));
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + j + 2));
    const unsigned same =
        unsigned(_mm_movemask_epi8(_mm_and_si128(_mm_cmpeq_epi8(a, b), _mm_cmpeq_epi8(b, c))));
    if (same) return j + size_t(std::countr_zero(same));
  }
#endif
  for (; j < limit; ++j)
    if (j + 2 < n && in[j] == in[j + 1] && in[j + 1] == in[j + 2]) return j;
  return limit;
}

std::int32_t load_i32(const unsigned char* p) {
  std::int32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

}  // namespace

void rle_compress_block(const unsigned char* in, size_t n, std::vector<unsigned char>& scratch,
                        std::vector<unsigned char>& out) {
  out.clear();
  if (n == 0) return;
  // The bytes split as ZIP and RLE store them: the even bytes first, then the odd ones; then
  // each byte after the first replaced by its difference from the one before, plus 128.
  scratch.resize(2 * n);
  unsigned char* split = scratch.data();
  unsigned char* t = scratch.data() + n;
  const size_t half = (n + 1) / 2;
  for (size_t k = 0; k < n / 2; ++k) {
    split[k] = in[2 * k];
    split[half + k] = in[2 * k + 1];
  }
  if (n & 1) split[half - 1] = in[n - 1];
  t[0] = split[0];
  for (size_t k = 1; k < n; ++k) t[k] = (unsigned char)(split[k] - split[k - 1] + 128);

  // Runs of 3 to 128 equal bytes as (count − 1, byte); the bytes between as (−count, bytes),
  // at most 127 at a time, a literal ending where three equal bytes start.
  out.resize(n + n / kMaxLiteral + 2);
  unsigned char* o = out.data();
  for (size_t i = 0; i < n;) {
    size_t j = run_end(t, n, i);
    if (j - i >= 3) {
      *o++ = (unsigned char)(j - i - 1);
      *o++ = t[i];
    } else {
      j = triple_start(t, n, j, std::min(n, i + kMaxLiteral));
      *o++ = (unsigned char)(-int(j - i));
      std::memcpy(o, t + i, j - i);
      o += j - i;
    }
    i = j;
  }
  out.resize(size_t(o - out.data()));
}

RleExrWriter::RleExrWriter(const std::string& path)
    : IOProxy(path, IOProxy::Write), file_(std::fopen(path.c_str(), "wb")) {
  if (!file_) {
    state_ = State::failed;
    why_ = "cannot create the file";
  }
}

RleExrWriter::~RleExrWriter() {
  if (file_) std::fclose(file_);
}

bool RleExrWriter::fail(const std::string& why) {
  if (state_ != State::failed) why_ = why;
  state_ = State::failed;
  return false;
}

bool RleExrWriter::put(const void* data, size_t n) {
  if (n && std::fwrite(data, 1, n, file_) != n) return fail("cannot write the file");
  written_ += int64_t(n);
  return true;
}

// The magic number, the version field and the attributes up to the empty name that ends
// them, if they have all arrived: written with the compression set to RLE. False when the
// header is incomplete (state unchanged) or not one this writer takes (failed).
bool RleExrWriter::parse_header() {
  const unsigned char* p = pending_.data() + read_;
  const size_t avail = pending_.size() - read_;
  if (avail < 8) return false;
  if (load_i32(p) != 20000630) return fail("not an EXR");
  const std::int32_t version = load_i32(p + 4);
  if (version & (0x200 | 0x800 | 0x1000)) return fail("not a single-part scanline EXR");
  size_t at = 8, compression_at = 0;
  bool has_window = false;
  for (;;) {
    const void* end_name = std::memchr(p + at, 0, avail - at);
    if (!end_name) return false;
    const size_t name_len = size_t(static_cast<const unsigned char*>(end_name) - (p + at));
    if (name_len == 0) {  // the end of the header
      ++at;
      break;
    }
    const std::string name(reinterpret_cast<const char*>(p + at), name_len);
    const size_t type_at = at + name_len + 1;
    const void* end_type = std::memchr(p + type_at, 0, avail - std::min(avail, type_at));
    if (type_at >= avail || !end_type) return false;
    const size_t type_len = size_t(static_cast<const unsigned char*>(end_type) - (p + type_at));
    const std::string type(reinterpret_cast<const char*>(p + type_at), type_len);
    const size_t size_at = type_at + type_len + 1;
    if (size_at + 4 > avail) return false;
    const std::int32_t size = load_i32(p + size_at);
    if (size < 0) return fail("a damaged header");
    const size_t value_at = size_at + 4;
    if (value_at + size_t(size) > avail) return false;
    if (name == "compression" && type == "compression" && size == 1) compression_at = value_at;
    if (name == "dataWindow" && type == "box2i" && size == 16) {
      y_min_ = load_i32(p + value_at + 4);
      const std::int32_t y_max = load_i32(p + value_at + 12);
      if (y_max < y_min_) return fail("an empty data window");
      blocks_ = size_t(int64_t(y_max) - y_min_ + 1);
      has_window = true;
    }
    at = value_at + size_t(size);
  }
  if (!compression_at || !has_window) return fail("a header without compression or dataWindow");
  if (p[compression_at] != 0) return fail("a file that is already compressed");
  std::vector<unsigned char> header(p, p + at);
  header[compression_at] = 1;  // RLE_COMPRESSION
  read_ += at;
  table_at_ = int64_t(at);
  offsets_.reserve(blocks_);
  state_ = State::table;
  return put(header.data(), header.size());
}

// Takes what it can of the pending bytes; false on failure.
bool RleExrWriter::consume() {
  for (;;) {
    const unsigned char* p = pending_.data() + read_;
    const size_t avail = pending_.size() - read_;
    if (state_ == State::failed) return false;
    if (state_ == State::header) {
      if (!parse_header()) return state_ != State::failed;
      continue;
    }
    if (state_ == State::table) {
      // OpenEXR's placeholder table; the offsets are written at close.
      if (avail < 8 * blocks_) break;
      const std::vector<unsigned char> zeros(8 * blocks_, 0);
      if (!put(zeros.data(), zeros.size())) return false;
      read_ += 8 * blocks_;
      state_ = State::blocks;
      continue;
    }
    if (state_ == State::done) {
      if (avail) return fail("bytes after the last block");
      break;
    }
    // A block: y, its size, its bytes.
    if (avail < 8) break;
    const std::int32_t y = load_i32(p), size = load_i32(p + 4);
    if (size < 0) return fail("a block of negative size");
    if (avail < 8 + size_t(size)) break;
    if (int64_t(y) != int64_t(y_min_) + int64_t(offsets_.size()))
      return fail("blocks out of order");
    rle_compress_block(p + 8, size_t(size), scratch_, packed_);
    offsets_.push_back(std::uint64_t(written_));
    const bool smaller = packed_.size() < size_t(size);
    const std::int32_t stored = smaller ? std::int32_t(packed_.size()) : size;
    if (!put(&y, 4) || !put(&stored, 4) || !put(smaller ? packed_.data() : p + 8, size_t(stored)))
      return false;
    read_ += 8 + size_t(size);
    if (offsets_.size() == blocks_) state_ = State::done;
  }
  // Drop what was consumed, now and then (a block arrives in several writes).
  if (read_ == pending_.size()) {
    pending_.clear();
    read_ = 0;
  } else if (read_ > (size_t(1) << 20)) {
    pending_.erase(pending_.begin(), pending_.begin() + std::ptrdiff_t(read_));
    read_ = 0;
  }
  return true;
}

size_t RleExrWriter::write(const void* buf, size_t size) {
  if (state_ == State::failed) return 0;
  if (pos_ != end_) {
    // OpenEXR filling in its offset table at the end: ours is written at close.
    const int64_t table_end = table_at_ + int64_t(8 * blocks_);
    if (state_ == State::done && pos_ >= table_at_ && pos_ + int64_t(size) <= table_end) {
      pos_ += int64_t(size);
      return size;
    }
    fail("a write before the end of the file");
    return 0;
  }
  const unsigned char* b = static_cast<const unsigned char*>(buf);
  pending_.insert(pending_.end(), b, b + size);
  pos_ += int64_t(size);
  end_ = pos_;
  return consume() ? size : 0;
}

bool RleExrWriter::seek(int64_t offset) {
  if (offset < 0 || offset > end_) return false;
  pos_ = offset;
  return true;
}

void RleExrWriter::close() {
  if (!file_) return;
  if (state_ == State::done) {
    // The offset table (little-endian 64-bit offsets, in the order of the blocks).
    if (std::fseek(file_, long(table_at_), SEEK_SET) != 0 ||
        std::fwrite(offsets_.data(), 8, offsets_.size(), file_) != offsets_.size())
      fail("cannot write the file");
  } else if (state_ != State::failed) {
    fail("the file ended before its last block");
  }
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!closed) fail("cannot write the file");
  complete_ = state_ == State::done;
}

}  // namespace hbil::io
