// exr_output_test.cpp: the EXR writer (io/exr_output.h) never writes a NaN or an infinity:
// a non-finite value is an internal error naming the frame, the layer and the pixel, and
// leaves no file; a finite value beyond the half range is stored as the largest half.
#include "io/exr_output.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "hbil/error.h"
#include "test_util.h"

namespace hbil::io {
namespace {

namespace fs = std::filesystem;
using test::expect_error;
using test::TempDir;

constexpr int kW = 9, kH = 70;  // more rows than one strip of the writer (64)

// A frame of ao, bentcone and irradiance with ordinary values.
AoFrame frame() {
  AoFrame f;
  f.width = kW;
  f.height = kH;
  const size_t n = size_t(kW) * kH;
  f.ao.assign(n, 0.75f);
  f.bent.assign(n, Vec3{0, 0, 1});
  f.cone_cos.assign(n, 0.5f);
  f.irradiance.assign(n, Vec3{0.25f, 0.5f, 1.0f});
  return f;
}

Params params() {
  Params p;
  p.outputs = {"ao", "bentcone", "irradiance"};
  return p;
}

Camera camera() {
  Camera c;
  c.width = kW;
  c.height = kH;
  c.fx = c.fy = 10;
  c.cx = kW / 2.0;
  c.cy = kH / 2.0;
  c.source = "test";
  return c;
}

std::string write(const std::string& final_path, const AoFrame& f, std::optional<int> frame) {
  return write_temporary(final_path, f, OIIO::ImageSpec(), params(), camera(), frame);
}

size_t files_in(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(ExrOutput, FiniteFrameIsWritten) {
  TempDir dir(test::test_name());
  const std::string tmp = write(dir / "f_0007.exr", frame(), 7);
  ASSERT_TRUE(fs::exists(tmp));
  const test::Pixels px = test::read_pixels(tmp);
  ASSERT_EQ(px.spec.width, kW);
  EXPECT_EQ(px.at(4, 66, px.channel("ao.Y")), 0.75f);
  EXPECT_EQ(px.at(4, 66, px.channel("irradiance.G")), 0.5f);
}

TEST(ExrOutput, NonFiniteValueIsAnInternalErrorAndLeavesNoFile) {
  TempDir dir(test::test_name());
  const float nan = std::numeric_limits<float>::quiet_NaN(),
              inf = std::numeric_limits<float>::infinity();
  // A float data layer, in the second strip of rows; a later pixel holds another NaN.
  AoFrame a = frame();
  a.ao[size_t(65) * kW + 3] = nan;
  a.ao[size_t(68) * kW + 1] = nan;
  expect_error(
      [&] { write(dir / "out/f_0007.exr", a, 7); }, Exit::failure,
      {"frame 7", dir / "out/f_0007.exr", "layer ao.Y", "non-finite value nan", "pixel (3, 65)"});
  EXPECT_EQ(files_in(dir.path()), 0u) << "the temporary must be removed";
  // A half colour layer: an infinity in green, in the first strip.
  AoFrame b = frame();
  b.irradiance[size_t(2) * kW + 8].y = -inf;
  expect_error([&] { write(dir / "out/f_0008.exr", b, std::nullopt); }, Exit::failure,
               {dir / "out/f_0008.exr", "layer irradiance.G", "-inf", "pixel (8, 2)"});
  EXPECT_EQ(files_in(dir.path()), 0u);
  // The bent vector: the first non-finite pixel wins over a later one in an earlier channel.
  AoFrame c = frame();
  c.bent[size_t(10) * kW + 5].z = nan;
  c.ao[size_t(11) * kW] = nan;
  expect_error([&] { write(dir / "out/f_0009.exr", c, 9); }, Exit::failure,
               {"layer bentcone.Z", "pixel (5, 10)"});
  EXPECT_EQ(files_in(dir.path()), 0u);
}

TEST(ExrOutput, FiniteValuesBeyondTheHalfRangeAreClampedNotInfinite) {
  TempDir dir(test::test_name());
  AoFrame f = frame();
  f.irradiance[0] = Vec3{1e6f, -1e9f, 65504.f};
  const test::Pixels px = test::read_pixels(write(dir / "f_0001.exr", f, 1));
  EXPECT_EQ(px.at(0, 0, px.channel("irradiance.R")), 65504.f);
  EXPECT_EQ(px.at(0, 0, px.channel("irradiance.G")), -65504.f);
  EXPECT_EQ(px.at(0, 0, px.channel("irradiance.B")), 65504.f);
}

}  // namespace
}  // namespace hbil::io
