// exr_deflate_test.cpp: the libdeflate scanline reader gives OpenEXR's own readPixels values,
// bit for bit, on every layout it takes, declines the others, and names the rows of a
// damaged block (io/exr_deflate.h).
//
// Files are written with OpenEXR itself: a data window that starts off the origin and whose
// height is not a multiple of ZIP's 16-row block, half, float and uint channels, smooth
// data (blocks that compress) and noise (blocks OpenEXR stores as they are).

#include "io/exr_deflate.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfTiledOutputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "hbil/error.h"
#include "io/layer_expr.h"
#include "test_util.h"

namespace hbil::io {
namespace {

using test::TempDir;

// 29 x 37 pixels from (-5, 3): three ZIP blocks, the last of 5 rows.
const Imath::Box2i kWindow(Imath::V2i(-5, 3), Imath::V2i(23, 39));
constexpr size_t kW = 29, kH = 37;

struct Channel {
  const char* name;
  Imf::PixelType type;
};
// Not in alphabetical order on purpose: the file stores them sorted.
const std::vector<Channel> kChannels = {
    {"view.Z", Imf::FLOAT}, {"view.A", Imf::HALF}, {"id", Imf::UINT}, {"view.N.X", Imf::HALF}};

// The value written to channel c at pixel i: smooth, or noise that does not compress.
uint32_t value_bits(size_t c, size_t i, bool noise, Imf::PixelType type) {
  static std::mt19937 rng(7);
  const float x = float(i % kW) / kW, y = float(i / kW) / kH;
  float v = noise ? std::uniform_real_distribution<float>(-100.f, 100.f)(rng)
                  : std::sin(3.f * x + float(c)) * 2.f + y;
  if (type == Imf::UINT) return noise ? uint32_t(rng()) : uint32_t(i * 3 + c);
  if (type == Imf::HALF) return Imath::half(v).bits();
  uint32_t b;
  std::memcpy(&b, &v, 4);
  return b;
}

void write_file(const std::string& path, Imf::Compression compression, bool noise, int tile = 0) {
  Imf::Header header(kWindow, kWindow);
  header.compression() = compression;
  std::vector<std::vector<uint32_t>> planes(kChannels.size(), std::vector<uint32_t>(kW * kH));
  Imf::FrameBuffer fb;
  for (size_t c = 0; c < kChannels.size(); ++c) {
    header.channels().insert(kChannels[c].name, Imf::Channel(kChannels[c].type));
    for (size_t i = 0; i < kW * kH; ++i) planes[c][i] = value_bits(c, i, noise, kChannels[c].type);
    if (kChannels[c].type == Imf::HALF)  // halves as 2-byte samples in 4-byte slots
      for (uint32_t& b : planes[c]) b &= 0xffff;
    fb.insert(kChannels[c].name,
              Imf::Slice::Make(kChannels[c].type, planes[c].data(), kWindow, 4, 4 * kW));
  }
  if (tile) {
    header.setTileDescription(Imf::TileDescription(tile, tile));
    Imf::TiledOutputFile out(path.c_str(), header);
    out.setFrameBuffer(fb);
    out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
  } else {
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(int(kH));
  }
}

// All channels as float, interleaved per pixel in kChannels' order, by `fast` or by OpenEXR.
struct Read {
  bool taken = false;
  std::vector<float> px = std::vector<float>(kW * kH * kChannels.size(), -1.f);
};
Read read(const std::string& path, bool fast) {
  Imf::InputFile file(path.c_str());
  Read r;
  const size_t n = kChannels.size();
  if (fast) {
    std::vector<ExrChannelTarget> targets;
    for (size_t c = 0; c < n; ++c) targets.push_back({kChannels[c].name, r.px.data() + c, n});
    r.taken = read_deflate_scanlines(file, targets);
    return r;
  }
  Imf::FrameBuffer fb;
  for (size_t c = 0; c < n; ++c)
    fb.insert(kChannels[c].name, Imf::Slice::Make(Imf::FLOAT, r.px.data() + c, kWindow,
                                                  sizeof(float) * n, sizeof(float) * n * kW));
  file.setFrameBuffer(fb);
  file.readPixels(kWindow.min.y, kWindow.max.y);
  r.taken = true;
  return r;
}

// How many of the file's blocks OpenEXR stored uncompressed (their size is the raw size).
int stored_blocks(const std::string& path, size_t block_rows) {
  Imf::InputFile file(path.c_str());
  const size_t line = kW * (4 + 2 + 4 + 2);
  int stored = 0;
  for (size_t row0 = 0; row0 < kH; row0 += block_rows) {
    const char* data;
    int size;
    file.rawPixelData(kWindow.min.y + int(row0), data, size);
    stored += size_t(size) == std::min(block_rows, kH - row0) * line;
  }
  return stored;
}

TEST(ExrDeflate, GivesOpenExrsValuesOnEveryLayoutItTakes) {
  TempDir dir{test::test_name()};
  struct Case {
    Imf::Compression compression;
    size_t block_rows;
    const char* name;
  };
  for (const Case& k :
       {Case{Imf::ZIP_COMPRESSION, 16, "zip"}, Case{Imf::ZIPS_COMPRESSION, 1, "zips"},
        Case{Imf::NO_COMPRESSION, 1, "none"}})
    for (bool noise : {false, true}) {
      SCOPED_TRACE(std::string(k.name) + (noise ? " noise" : " smooth"));
      const std::string path = dir / (std::string(k.name) + (noise ? "-noise" : "") + ".exr");
      write_file(path, k.compression, noise);
      const int blocks = int((kH + k.block_rows - 1) / k.block_rows);
      const int stored = stored_blocks(path, k.block_rows);
      if (k.compression == Imf::NO_COMPRESSION)
        EXPECT_EQ(stored, blocks);
      else if (noise)
        EXPECT_EQ(stored, blocks) << "noise does not shrink: every block is stored as it is";
      else
        EXPECT_EQ(stored, 0) << "smooth data shrinks: every block is inflated";
      const Read fast = read(path, true), ref = read(path, false);
      ASSERT_TRUE(fast.taken);
      ASSERT_EQ(fast.px.size(), ref.px.size());
      EXPECT_EQ(0, std::memcmp(fast.px.data(), ref.px.data(), ref.px.size() * sizeof(float)));
      EXPECT_NE(fast.px[kW * kChannels.size() + 1], -1.f) << "a sample was converted";
    }
}

TEST(ExrDeflate, DeclinesOtherLayoutsAndReadsNothing) {
  TempDir dir{test::test_name()};
  const std::string rle = dir / "rle.exr", tiled = dir / "tiled.exr";
  write_file(rle, Imf::RLE_COMPRESSION, false);
  write_file(tiled, Imf::ZIP_COMPRESSION, false, 16);
  for (const std::string& path : {rle, tiled}) {
    const Read fast = read(path, true);
    EXPECT_FALSE(fast.taken) << path;
    for (float v : fast.px) ASSERT_EQ(v, -1.f) << path;
  }
  // A channel the file lacks: declined, so that OpenEXR's own rules apply.
  write_file(dir / "zip.exr", Imf::ZIP_COMPRESSION, false);
  Imf::InputFile file((dir / "zip.exr").c_str());
  float sink = -1.f;
  EXPECT_FALSE(read_deflate_scanlines(file, {{"view.absent", &sink, 1}}));
  EXPECT_EQ(sink, -1.f);
}

// Flips a byte of the last block's checksum: a ZIP file ends with that block's zlib stream,
// whose last four bytes are its checksum.
void damage_last_block(const std::string& path) {
  std::vector<char> bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  bytes[bytes.size() - 2] ^= 0x5a;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

TEST(ExrDeflate, DamagedBlockIsNamedByItsRows) {
  TempDir dir{test::test_name()};
  const std::string path = dir / "zip.exr";
  write_file(path, Imf::ZIP_COMPRESSION, false);
  damage_last_block(path);
  Imf::InputFile file(path.c_str());
  std::vector<float> sink(kW * kH);
  try {
    read_deflate_scanlines(file, {{"view.Z", sink.data(), 1}});
    FAIL() << "a damaged block was read without an error";
  } catch (const std::runtime_error& e) {
    // Blocks start at rows 3, 19 and 35; the last holds rows 35-39.
    EXPECT_TRUE(test::contains(e.what(), "rows 35-39")) << e.what();
  }
}

// Every byte of a file flipped in turn: the read throws, declines the file, or gives the clean
// file's values; it never ends in a signal or in other values. (Flipped bytes that change
// nothing, in an attribute hbil does not read, are allowed to do nothing.)
TEST(ExrDeflate, EveryFlippedByteIsAnErrorOrHarmless) {
  TempDir dir{test::test_name()};
  const std::string clean = dir / "zip.exr", bad = dir / "bad.exr";
  write_file(clean, Imf::ZIP_COMPRESSION, false);
  const Read ref = read(clean, true);
  ASSERT_TRUE(ref.taken);
  std::vector<char> bytes;
  {
    std::ifstream in(clean, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  int errors = 0, declined = 0, same = 0;
  for (size_t at = 0; at < bytes.size(); ++at) {
    std::vector<char> b = bytes;
    b[at] = char(b[at] ^ 0xff);
    {
      std::ofstream out(bad, std::ios::binary | std::ios::trunc);
      out.write(b.data(), std::streamsize(b.size()));
    }
    try {
      const Read r = read(bad, true);
      if (!r.taken) {
        ++declined;
        continue;
      }
      ASSERT_EQ(0, std::memcmp(r.px.data(), ref.px.data(), ref.px.size() * sizeof(float)))
          << "byte " << at << " flipped gave other values without an error";
      ++same;
    } catch (const std::exception&) {
      ++errors;
    }
  }
  // Every byte of the pixel data is covered by its block's checksum, and the offsets and the
  // header by OpenEXR's checks: only a few attributes can change unnoticed.
  EXPECT_GT(errors, int(bytes.size()) * 9 / 10)
      << declined << " declined, " << same << " unchanged";
}

// ImageFile (layer_expr.h), which `hbil compare`, `hbil bench` and `calibration` read files
// with, takes this reader where it can: every layout gives OpenImageIO's own values, one
// channel or a range, and a damaged file is an error naming it.
TEST(ExrDeflate, ImageFileReadsEveryLayoutAsOpenImageIoDoes) {
  TempDir dir{test::test_name()};
  struct Case {
    Imf::Compression compression;
    int tile;
    const char* name;
  };
  for (const Case& k :
       {Case{Imf::ZIP_COMPRESSION, 0, "zip"}, Case{Imf::ZIPS_COMPRESSION, 0, "zips"},
        Case{Imf::NO_COMPRESSION, 0, "none"}, Case{Imf::RLE_COMPRESSION, 0, "rle"},
        Case{Imf::ZIP_COMPRESSION, 16, "tiled"}}) {
    SCOPED_TRACE(k.name);
    const std::string path = dir / (std::string(k.name) + ".exr");
    write_file(path, k.compression, false, k.tile);
    ImageFile f(path);
    const int n = f.spec().nchannels;
    ASSERT_EQ(n, int(kChannels.size()));
    auto oiio = [&](int begin, int end) {
      auto in = OIIO::ImageInput::open(path);
      std::vector<float> v(kW * kH * size_t(end - begin));
      EXPECT_TRUE(in && in->read_image(0, 0, begin, end, OIIO::TypeDesc::FLOAT, v.data()));
      return v;
    };
    const std::vector<float> all = f.read_range(0, n), want = oiio(0, n);
    ASSERT_EQ(all.size(), want.size());
    EXPECT_EQ(0, std::memcmp(all.data(), want.data(), want.size() * sizeof(float)));
    for (int c = 0; c < n; ++c) {
      const std::vector<float> one = f.read(c), want_one = oiio(c, c + 1);
      EXPECT_EQ(0, std::memcmp(one.data(), want_one.data(), want_one.size() * sizeof(float)))
          << f.spec().channelnames[size_t(c)];
    }
    const std::vector<float> mid = f.read_range(1, 3), want_mid = oiio(1, 3);
    EXPECT_EQ(0, std::memcmp(mid.data(), want_mid.data(), want_mid.size() * sizeof(float)));
  }
  // The last block damaged: an error that names the file.
  const std::string path = dir / "zip.exr";
  damage_last_block(path);
  ImageFile f(path);
  try {
    f.read_range(0, f.spec().nchannels);
    FAIL() << "a damaged file was read without an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Exit::input);
    EXPECT_TRUE(test::contains(e.what(), path)) << e.what();
  }
}

}  // namespace
}  // namespace hbil::io
