// exr_rle.h: OpenEXR's RLE compression, done by hbil for the frames it writes.
//
// OpenEXR compresses an RLE block (one scanline of every channel) byte by byte; over a
// 1920x1080 frame of default outputs that is most of the writer's time. The file format is
// the same whoever compresses, so hbil has OpenEXR write the frame uncompressed into an
// IOProxy (RleExrWriter) that compresses each block as it arrives, 16 bytes at a time where
// it can, and writes the RLE file. Its choices are OpenEXR's (the same split of even and odd
// bytes, the same predictor, the same runs and literals, a block stored as it is when
// compressing does not make it smaller), so the file is the one OpenEXR would have written,
// byte for byte (tests/exr_rle_test.cpp).
#pragma once

#include <OpenImageIO/filesystem.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace hbil::io {

// Compresses one block of n bytes as OpenEXR's RLE does, into out (resized to the result;
// `scratch` is working memory, kept by the caller from block to block).
void rle_compress_block(const unsigned char* in, size_t n, std::vector<unsigned char>& scratch,
                        std::vector<unsigned char>& out);

// An OpenImageIO IOProxy for OpenEXR's writer: it takes the bytes of an uncompressed
// single-part scanline EXR (magic, header, line offset table, blocks in increasing y, then
// the offset table again at close) and writes the same image, RLE-compressed, to `path`.
// Anything else it is given (tiles, several parts, a compression other than none, blocks out
// of order) makes write() fail, which OpenImageIO reports as a write error. close() writes
// the offset table and says whether the whole file was written.
class RleExrWriter final : public OIIO::Filesystem::IOProxy {
 public:
  explicit RleExrWriter(const std::string& path);
  ~RleExrWriter() override;
  RleExrWriter(const RleExrWriter&) = delete;
  RleExrWriter& operator=(const RleExrWriter&) = delete;

  const char* proxytype() const override { return "hbil-rle"; }
  size_t write(const void* buf, size_t size) override;
  bool seek(int64_t offset) override;
  int64_t tell() override { return pos_; }
  size_t size() const override { return size_t(end_); }
  void close() override;
  // After close(): whether every block and the offset table reached the file.
  bool complete() const { return complete_; }
  // Why it failed (empty when it did not).
  const std::string& why() const { return why_; }

 private:
  enum class State { header, table, blocks, done, failed };
  bool consume();
  bool parse_header();
  bool put(const void* data, size_t n);
  bool fail(const std::string& why);

  std::FILE* file_ = nullptr;
  State state_ = State::header;
  std::vector<unsigned char> pending_;  // bytes received and not yet consumed (from `read_`)
  size_t read_ = 0;
  int64_t pos_ = 0, end_ = 0;  // OpenEXR's position in the uncompressed file, and its end
  int64_t written_ = 0;        // bytes in the RLE file
  int64_t table_at_ = 0;       // where the offset table starts (the same in both files)
  int y_min_ = 0;
  size_t blocks_ = 0;
  std::vector<std::uint64_t> offsets_;  // of the RLE file's blocks, in order
  std::vector<unsigned char> scratch_, packed_;
  bool complete_ = false;
  std::string why_;
};

}  // namespace hbil::io
