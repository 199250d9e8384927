// exr_rle_test.cpp: hbil's RLE writer (io/exr_rle.h) writes, byte for byte, the file
// OpenEXR's own RLE compressor writes, and its blocks decode to the bytes given.
#include "io/exr_rle.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "test_util.h"

namespace hbil::io {
namespace {

using test::TempDir;

// The format's decoder, written from its description: a count byte c >= 0 is followed by one
// byte repeated c + 1 times, c < 0 by −c bytes as they are; then the running sum of
// (byte − 128) after the first, and the two halves (even bytes, odd bytes) interleaved.
std::vector<unsigned char> rle_decode(const std::vector<unsigned char>& in, size_t n) {
  std::vector<unsigned char> t;
  for (size_t i = 0; i < in.size();) {
    const int c = static_cast<signed char>(in[i++]);
    if (c >= 0) {
      t.insert(t.end(), size_t(c) + 1, in.at(i++));
    } else {
      for (int k = 0; k < -c; ++k) t.push_back(in.at(i++));
    }
  }
  EXPECT_EQ(t.size(), n);
  for (size_t k = 1; k < t.size(); ++k) t[k] = (unsigned char)(t[k - 1] + t[k] - 128);
  std::vector<unsigned char> out(t.size());
  const size_t half = (t.size() + 1) / 2;
  for (size_t k = 0; k < t.size(); ++k) out[k] = k % 2 == 0 ? t[k / 2] : t[half + k / 2];
  return out;
}

// Bytes with runs of every length around the format's limits, and noise between them.
std::vector<unsigned char> mixed_bytes(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<unsigned char> v;
  const size_t runs[] = {1, 2, 3, 4, 15, 16, 17, 126, 127, 128, 129, 130, 255, 256, 300};
  while (v.size() < n) {
    const size_t run = runs[rng() % std::size(runs)];
    const unsigned char b = (unsigned char)(rng() & 3);  // few values: triples appear by chance
    if (rng() % 2)
      v.insert(v.end(), run, b);
    else
      for (size_t k = 0; k < run; ++k) v.push_back((unsigned char)rng());
  }
  v.resize(n);
  return v;
}

TEST(RleBlock, DecodesToTheBytesGiven) {
  std::vector<unsigned char> scratch, packed;
  for (size_t n :
       {size_t(0), size_t(1), size_t(2), size_t(3), size_t(17), size_t(1001), size_t(40000)}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const std::vector<unsigned char> in = mixed_bytes(n, seed);
      rle_compress_block(in.data(), in.size(), scratch, packed);
      EXPECT_EQ(rle_decode(packed, n), in) << n << " bytes, seed " << seed;
    }
  }
  // A constant block of 1000 bytes: after the predictor one byte, then 999 of 128, in runs
  // of at most 128: (0, b) is a literal of one, then 7 full runs and one of 103.
  const std::vector<unsigned char> flat(1000, 7);
  rle_compress_block(flat.data(), flat.size(), scratch, packed);
  ASSERT_EQ(packed.size(), 2u + 8 * 2);
  EXPECT_EQ(packed[0], 0xff);  // a literal of one byte
  EXPECT_EQ(packed[1], 7);
  EXPECT_EQ(packed[2], 127);  // 128 x 128
  EXPECT_EQ(packed[3], 128);
  EXPECT_EQ(packed[16], 102);  // the last 103
}

// An image with float and half channels, flat areas and noise, written by OpenImageIO:
// with compression rle to `plain`, and with compression none through RleExrWriter to `ours`.
void write_both(const std::string& plain, const std::string& ours, int w, int h, int y0) {
  OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::FLOAT);
  spec.y = y0;
  spec.full_y = y0;
  spec.channelnames = {"a.Y", "b.R", "b.G", "b.B"};
  spec.channelformats = {OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::HALF, OIIO::TypeDesc::HALF,
                         OIIO::TypeDesc::HALF};
  spec.attribute("a.long.attribute.name.beyond.thirty.one.characters", "some text");
  // A fixed capDate: OpenImageIO stamps the current second otherwise, and two writes that
  // straddle a second would differ there.
  spec.attribute("DateTime", "2026:01:01 00:00:00");
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<unsigned char> pixels;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool flat = (x / 7 + y / 5) % 3 == 0;
      const float a = flat ? 0.5f : u(rng);
      const unsigned char* pa = reinterpret_cast<const unsigned char*>(&a);
      pixels.insert(pixels.end(), pa, pa + 4);
      for (int c = 0; c < 3; ++c) {
        const Imath::half v(flat ? 0.25f : u(rng));
        const std::uint16_t bits = v.bits();
        pixels.push_back((unsigned char)(bits & 0xff));
        pixels.push_back((unsigned char)(bits >> 8));
      }
    }
  {
    OIIO::ImageSpec s = spec;
    s.attribute("compression", "rle");
    auto out = OIIO::ImageOutput::create(plain);
    ASSERT_TRUE(out->open(plain, s));
    ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, pixels.data()));
    ASSERT_TRUE(out->close());
  }
  {
    OIIO::ImageSpec s = spec;
    s.attribute("compression", "none");
    RleExrWriter proxy(ours);
    auto out = OIIO::ImageOutput::create(ours);
    ASSERT_TRUE(out->set_ioproxy(&proxy));
    ASSERT_TRUE(out->open(ours, s));
    ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, pixels.data()));
    ASSERT_TRUE(out->close());
    out.reset();
    proxy.close();
    ASSERT_TRUE(proxy.complete()) << proxy.why();
  }
}

std::vector<char> bytes_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

TEST(RleExrWriter, WritesTheFileOpenExrWrites) {
  TempDir dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  for (const auto& [w, h, y0] : {std::tuple{37, 23, 0}, std::tuple{256, 9, -4},
                                 std::tuple{1, 1, 11}, std::tuple{1000, 3, 2}}) {
    const std::string plain = dir / "plain.exr", ours = dir / "ours.exr";
    write_both(plain, ours, w, h, y0);
    const std::vector<char> a = bytes_of(plain), b = bytes_of(ours);
    ASSERT_GT(a.size(), 100u);
    EXPECT_TRUE(a == b) << w << "x" << h << ": " << a.size() << " against " << b.size() << " bytes";
    // And OpenImageIO reads it as RLE, with the same pixels.
    auto in = OIIO::ImageInput::open(ours);
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().get_string_attribute("compression"), "rle");
    EXPECT_EQ(in->spec().y, y0);
    std::vector<float> pa(size_t(w) * h * 4), pb(pa.size());
    ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::FLOAT, pb.data()));
    auto ref = OIIO::ImageInput::open(plain);
    ASSERT_TRUE(ref->read_image(0, 0, 0, 4, OIIO::TypeDesc::FLOAT, pa.data()));
    EXPECT_EQ(pa, pb);
  }
}

// A stream it does not take (already compressed) fails the write, and close says so.
TEST(RleExrWriter, RefusesACompressedStream) {
  TempDir dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  const std::string path = dir / "zip.exr";
  OIIO::ImageSpec spec(8, 8, 1, OIIO::TypeDesc::FLOAT);
  spec.attribute("compression", "zip");
  RleExrWriter proxy(path);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out->set_ioproxy(&proxy));
  const std::vector<float> pixels(64, 0.5f);
  const bool ok = out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) &&
                  out->close();
  EXPECT_FALSE(ok);
  out.reset();
  proxy.close();
  EXPECT_FALSE(proxy.complete());
  EXPECT_EQ(proxy.why(), "a file that is already compressed");
}

}  // namespace
}  // namespace hbil::io
