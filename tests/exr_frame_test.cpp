// exr_frame_test.cpp: channel lookup, reading only the needed fields, data checks and the
// camera sources of one input frame (io/exr_frame.h).
//
// Small synthetic multilayer EXRs with Blender 3.4 channel names are written per test;
// the Position solve uses the real room_poles frame 1 without its sidecar.

#include "io/exr_frame.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "io/camera_io.h"
#include "io/header_size.h"
#include "test_util.h"

namespace hbil::io {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::contains;
using test::expect_error;
using test::TempDir;

constexpr int kW = 24, kH = 16;
constexpr double kSolvedRmsPx = 0.5;      // what find_camera accepts by default
constexpr double kSolvedFocalRel = 0.01;  // solved fx, fy against the sidecar's

// Blender-like G-buffer channels of one view layer, in the order written.
std::vector<std::string> blender_channels(const std::string& layer, bool normal = true,
                                          bool position = true, bool alpha = true) {
  std::vector<std::string> c;
  if (alpha) c.insert(c.end(), {"Combined.R", "Combined.G", "Combined.B", "Combined.A"});
  c.push_back("Depth.Z");
  if (normal) c.insert(c.end(), {"Normal.X", "Normal.Y", "Normal.Z"});
  if (position) c.insert(c.end(), {"Position.X", "Position.Y", "Position.Z"});
  c.insert(c.end(), {"AO.R", "AO.G", "AO.B"});
  for (auto& s : c) s = layer + "." + s;
  return c;
}

// Distinct, exactly representable values per field so that a mix-up shows.
float depth_at(int x, int y) {
  return 2.0f + 0.25f * x + 0.125f * y;
}
Vec3 normal_at(int x, int y) {
  return {0.0625f * x, -0.5f, 0.03125f * y};
}
Vec3 position_at(int x, int y) {
  return {float(x), float(y), 100.0f};
}

float value_for(const std::string& name, int x, int y) {
  auto ends = [&](const char* t) { return name.ends_with(t); };
  if (ends("Depth.Z")) return depth_at(x, y);
  if (ends("Normal.X")) return normal_at(x, y).x;
  if (ends("Normal.Y")) return normal_at(x, y).y;
  if (ends("Normal.Z")) return normal_at(x, y).z;
  if (ends("Position.X")) return position_at(x, y).x;
  if (ends("Position.Y")) return position_at(x, y).y;
  if (ends("Position.Z")) return position_at(x, y).z;
  if (ends("Combined.A")) return x < kW / 2 ? 1.0f : 0.5f;
  return 0.25f;
}

void write_gbuffer(const std::string& path, const std::vector<std::string>& channels, int w = kW,
                   int h = kH) {
  test::write_exr(path, w, h, channels,
                  [&](int x, int y, int c) { return value_for(channels[c], x, y); });
}

class ExrFrame : public ::testing::Test {
 protected:
  TempDir dir{test::test_name()};
  std::string file(const std::string& name) const { return dir / name; }
};

TEST_F(ExrFrame, DetectsTheViewLayerAndResolvesEveryField) {
  const std::string path = file("frame_0007.exr");
  write_gbuffer(path, blender_channels("MyLayer"));
  const InputFrame f = open_frame(path, 7, Params{});
  EXPECT_EQ(f.view_layer, "MyLayer");
  EXPECT_EQ(f.spec.width, kW);
  EXPECT_EQ(f.spec.height, kH);
  for (const char* field : {"depth", "normal", "position", "alpha"})
    EXPECT_TRUE(f.has(field)) << field;
  EXPECT_EQ(f.wanted.at("depth"), std::vector<std::string>{"MyLayer.Depth.Z"});
  EXPECT_EQ(f.wanted.at("normal"),
            (std::vector<std::string>{"MyLayer.Normal.X", "MyLayer.Normal.Y", "MyLayer.Normal.Z"}));
  EXPECT_EQ(f.wanted.at("alpha"), std::vector<std::string>{"MyLayer.Combined.A"});
  for (const auto& [field, idx] : f.channels)
    for (size_t k = 0; k < idx.size(); ++k)
      EXPECT_EQ(f.spec.channelnames[idx[k]], f.wanted.at(field)[k]) << field;
  EXPECT_EQ(f.where(), "frame 7 (" + path + ")");
}

TEST_F(ExrFrame, GivenViewLayerSelectsAmongSeveral) {
  const std::string path = file("two_layers.exr");
  auto channels = blender_channels("Back");
  for (const auto& c : blender_channels("Front")) channels.push_back(c);
  write_gbuffer(path, channels);
  Params p;
  p.view_layer = "Front";
  const InputFrame f = open_frame(path, 1, p);
  EXPECT_EQ(f.view_layer, "Front");
  EXPECT_EQ(f.spec.channelnames[f.channels.at("depth")[0]], "Front.Depth.Z");
  EXPECT_EQ(f.spec.channelnames[f.channels.at("normal")[2]], "Front.Normal.Z");
}

TEST_F(ExrFrame, PresetMapsChannelsOfAnotherRenderer) {
  // No view layer, short names, normal mapped by an explicit list in reversed order so
  // that it is read channel by channel.
  const std::string path = file("other.exr");
  const std::vector<std::string> channels = {"N.X", "N.Y", "N.Z", "R", "G", "B", "Z"};
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    const Vec3 n = normal_at(x, y);
    switch (c) {
      case 0:
        return n.x;
      case 1:
        return n.y;
      case 2:
        return n.z;
      case 6:
        return depth_at(x, y);
      default:
        return 0.5f;
    }
  });
  Params p = apply_set(Params{}, R"(passes.normal=["N.Z","N.Y","N.X"])");
  p = apply_set(p, R"(passes.depth=["Z"])");
  const InputFrame f = open_frame(path, 3, p);
  EXPECT_EQ(f.view_layer, "");
  ASSERT_TRUE(f.has("normal"));
  ASSERT_TRUE(f.has("depth"));
  EXPECT_FALSE(f.has("position"));
  EXPECT_FALSE(f.has("alpha"));
  const auto need = fields_needed(f, p);
  EXPECT_EQ(need, (std::vector<std::string>{"depth", "normal"}));
  const GBuffer g = read_fields(f, need, p);
  ASSERT_EQ(g.depth.size(), size_t(kW * kH));
  ASSERT_EQ(g.normal.size(), size_t(kW * kH));
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      ASSERT_EQ(g.depth[i], depth_at(x, y)) << x << "," << y;
      const Vec3 n = normal_at(x, y);
      ASSERT_EQ(g.normal[i].x, n.z) << x << "," << y;  // reversed by the mapping
      ASSERT_EQ(g.normal[i].y, n.y) << x << "," << y;
      ASSERT_EQ(g.normal[i].z, n.x) << x << "," << y;
    }
}

TEST_F(ExrFrame, MissingNormalNamesFrameFileAndChannel) {
  const std::string path = file("frame_0005.exr");
  write_gbuffer(path, blender_channels("ViewLayer", /*normal=*/false));
  const Params p;
  const InputFrame f = open_frame(path, 5, p);
  EXPECT_FALSE(f.has("normal"));
  expect_error([&] { fields_needed(f, p); }, Exit::missing_pass,
               {"frame 5", path, "ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z",
                "passes.normal"});
}

TEST_F(ExrFrame, MissingDepthFallsBackToPosition) {
  const std::string path = file("frame_0001.exr");
  auto channels = blender_channels("ViewLayer");
  std::erase(channels, "ViewLayer.Depth.Z");
  write_gbuffer(path, channels);
  const Params p;
  const InputFrame f = open_frame(path, 1, p);
  EXPECT_EQ(f.view_layer, "ViewLayer") << "detected from Normal when Depth is absent";
  EXPECT_EQ(fields_needed(f, p), (std::vector<std::string>{"position", "normal", "alpha"}));
}

TEST_F(ExrFrame, MissingDepthAndPositionIsMissingPass) {
  const std::string path = file("frame_0002.exr");
  auto channels = blender_channels("ViewLayer", true, /*position=*/false);
  std::erase(channels, "ViewLayer.Depth.Z");
  write_gbuffer(path, channels);
  const Params p;
  const InputFrame f = open_frame(path, 2, p);
  expect_error([&] { fields_needed(f, p); }, Exit::missing_pass,
               {"frame 2", path, "ViewLayer.Depth.Z", "ViewLayer.Position.X"});
}

TEST_F(ExrFrame, NonFiniteDepthNamesFileFrameChannelAndPixel) {
  const std::string path = file("frame_0009.exr");
  const auto channels = blender_channels("ViewLayer");
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    if (channels[c] == "ViewLayer.Depth.Z" && x == 5 && y == 3)
      return std::numeric_limits<float>::quiet_NaN();
    return value_for(channels[c], x, y);
  });
  const Params p;
  const InputFrame f = open_frame(path, 9, p);
  expect_error([&] { read_fields(f, fields_needed(f, p), p); }, Exit::bad_data,
               {"frame 9", path, "ViewLayer.Depth.Z", "non-finite depth", "pixel (5, 3)", "nan"});
}

TEST_F(ExrFrame, NegativeDepthNamesFileFrameChannelAndPixel) {
  const std::string path = file("frame_0010.exr");
  const auto channels = blender_channels("ViewLayer");
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    if (channels[c] == "ViewLayer.Depth.Z" && x == kW - 1 && y == kH - 1) return -0.75f;
    return value_for(channels[c], x, y);
  });
  const Params p;
  const InputFrame f = open_frame(path, 10, p);
  expect_error(
      [&] { read_fields(f, fields_needed(f, p), p); }, Exit::bad_data,
      {"frame 10", path, "ViewLayer.Depth.Z", "negative depth", "pixel (23, 15)", "-0.75"});
}

TEST_F(ExrFrame, InfiniteNormalIsBadData) {
  const std::string path = file("frame_0011.exr");
  const auto channels = blender_channels("ViewLayer");
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    if (channels[c] == "ViewLayer.Normal.Y" && x == 0 && y == 1)
      return std::numeric_limits<float>::infinity();
    return value_for(channels[c], x, y);
  });
  const Params p;
  const InputFrame f = open_frame(path, 11, p);
  expect_error([&] { read_fields(f, fields_needed(f, p), p); }, Exit::bad_data,
               {"frame 11", path, "ViewLayer.Normal.Y", "pixel (0, 1)", "inf"});
}

// A channel list that does not end within its attribute's size: OpenEXR reads on into the
// next attribute and took a pixel type of 3 from there, on which OpenImageIO aborted (found
// by tests/fuzz/fuzz_frame). One that ends before its size: OpenEXR goes on reading
// attributes from the list's end, the walk from the claimed size, and it missed a data window
// of 16646160x9 that OpenEXR sized its line buffers from (found by tests/fuzz/fuzz_povray).
// Refused, exit 3, before OpenImageIO opens the file, whether the list's end or its last
// channel lies beyond the size, or the size beyond the list's end.
TEST(ExrLayouts, ChannelListNotEndingAtItsSizeIsRefusedBeforeReading) {
  TempDir dir{test::test_name()};
  std::ifstream in(test::kRoomPoles + "/frame_0001.exr", std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t size_at = good.find(std::string("channels\0chlist\0", 16)) + 16;
  ASSERT_LT(size_at, good.size());
  const uint32_t size = uint32_t(uint8_t(good[size_at])) |
                        uint32_t(uint8_t(good[size_at + 1])) << 8 |
                        uint32_t(uint8_t(good[size_at + 2])) << 16;
  struct Case {
    int32_t change;  // to the claimed size
    const char* message;
  } cases[] = {
      {-1, "the channel list has no end within its size"},
      {-5,
       "the channel list ends inside channel \"ViewLayer.Vector.Z\""},  // the last, alphabetically
      {6, "the channel list ends 6 bytes before its attribute's size"}};  // the next name's 6
  for (const Case& c : cases) {
    SCOPED_TRACE(c.message);
    std::string bytes = good;
    const uint32_t v = uint32_t(int64_t(size) + c.change);
    for (int b = 0; b < 4; ++b) bytes[size_at + b] = char((v >> (8 * b)) & 0xff);
    const std::string damaged = dir / "damaged.exr";
    std::ofstream(damaged, std::ios::binary | std::ios::trunc) << bytes;
    expect_error([&] { open_frame(damaged, 1, Params{}); }, Exit::input,
                 {damaged, "damaged OpenEXR header", c.message});
  }
}

// OpenEXR reads a fixed-size value by its type, whatever size the attribute claims, and reads
// on from there; a walk that skips the claimed size is then out of step with it, and missed an
// attribute claiming 1.7 GB that OpenEXR allocated (found by tests/fuzz/fuzz_frame). Such a
// header is refused, exit 3, and so is a name of more than 255 characters.
TEST(ExrLayouts, FixedSizeAttributeOfAnotherSizeOrOverlongNameIsRefused) {
  TempDir dir{test::test_name()};
  std::ifstream in(test::kRoomPoles + "/frame_0001.exr", std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string attr("screenWindowWidth\0float\0", 24);
  const size_t at = good.find(attr);
  ASSERT_NE(at, std::string::npos);
  {
    std::string bytes = good;
    bytes[at + attr.size()] = 8;  // the float's size: 8 instead of 4
    const std::string damaged = dir / "size.exr";
    std::ofstream(damaged, std::ios::binary | std::ios::trunc) << bytes;
    expect_error(
        [&] { open_frame(damaged, 1, Params{}); }, Exit::input,
        {damaged, "attribute \"screenWindowWidth\" (float) claims 8 bytes, its type has 4"});
  }
  {
    // The attribute's name run on over 300 characters (its NUL and the type overwritten).
    std::string bytes = good;
    for (size_t k = 0; k < 300; ++k) bytes[at + k] = 'n';
    const std::string damaged = dir / "name.exr";
    std::ofstream(damaged, std::ios::binary | std::ios::trunc) << bytes;
    expect_error([&] { open_frame(damaged, 1, Params{}); }, Exit::input,
                 {damaged, "a name of more than 255 characters"});
  }
}

// A channel of an undefined pixel type made OpenImageIO abort the process (found by
// tests/fuzz/fuzz_frame), and a sampling of 0 would divide by zero: both refused, exit 3.
TEST(ExrLayouts, UndefinedPixelTypeOrSamplingIsRefusedBeforeReading) {
  TempDir dir{test::test_name()};
  std::ifstream in(test::kRoomPoles + "/frame_0001.exr", std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // "channels\0chlist\0", the list's size (4 bytes), then the first channel's name.
  const size_t list = good.find(std::string("channels\0chlist\0", 16)) + 16 + 4;
  const size_t name_end = good.find('\0', list);
  const std::string first = good.substr(list, name_end - list);
  ASSERT_EQ(first, "BackFaces.Depth.Z");
  struct Case {
    size_t offset;  // from the end of the name
    const char* message;
  } cases[] = {{1, "has pixel type 3"}, {9, "has sampling 0x1"}, {13, "has sampling 1x0"}};
  for (const Case& c : cases) {
    std::string bytes = good;
    const int value = c.offset == 1 ? 3 : 0;
    for (int b = 0; b < 4; ++b) bytes[name_end + c.offset + b] = char(b == 0 ? value : 0);
    const std::string damaged = dir / "damaged.exr";
    std::ofstream(damaged, std::ios::binary | std::ios::trunc) << bytes;
    expect_error([&] { open_frame(damaged, 1, Params{}); }, Exit::input,
                 {damaged, "damaged OpenEXR header", "\"" + first + "\"", c.message});
  }
}

// Finite values no render writes, whose products would overflow float in the gather and
// reach the output as Inf (found by tests/fuzz/fuzz_frame: -1.7e38 in every pass): refused
// like non-finite ones, at the bound and not below it.
TEST_F(ExrFrame, ColourMotionAndAlphaBeyondTheirBoundsAreBadData) {
  auto channels = blender_channels("ViewLayer");
  for (const char* c : {"DiffCol.R", "DiffCol.G", "DiffCol.B", "Emit.R", "Emit.G", "Emit.B",
                        "Vector.X", "Vector.Y", "Vector.Z", "Vector.W"})
    channels.push_back(std::string("ViewLayer.") + c);
  struct Case {
    const char* channel;
    float value;
    bool refused;
    const char* why;
  } cases[] = {{"ViewLayer.DiffCol.G", 1000.f, false, ""},
               {"ViewLayer.DiffCol.G", 1001.f, true, "diffcol beyond +-1000 (an albedo)"},
               {"ViewLayer.Emit.B", 1e9f, false, ""},
               {"ViewLayer.Emit.B", -2e9f, true, "emit beyond +-1e9"},
               {"ViewLayer.Vector.X", -1e6f, false, ""},
               {"ViewLayer.Vector.Y", 3e6f, true, "vector beyond +-1e6 pixels"},
               // The composite's alpha (a NaN there reached the output; found by fuzz_frame).
               {"ViewLayer.Combined.A", -1e9f, false, ""},
               {"ViewLayer.Combined.A", std::nanf(""), true, "non-finite alpha"},
               {"ViewLayer.Combined.A", 2e9f, true, "alpha beyond +-1e9"}};
  Params p;
  p.outputs = {"ao", "composite"};
  p.passes["emit"] = "Emit";
  int k = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.channel) + " = " + std::to_string(c.value));
    const std::string path = file("bound" + std::to_string(k++) + ".exr");
    test::write_exr(path, kW, kH, channels, [&](int x, int y, int ch) {
      if (channels[ch] == c.channel && x == 2 && y == 7) return c.value;
      if (channels[ch].find("Vector") != std::string::npos) return 0.25f;
      return value_for(channels[ch], x, y);
    });
    const InputFrame f = open_frame(path, 1, p);
    std::vector<std::string> fields = {"depth", "normal", "diffcol", "emit", "vector", "alpha"};
    if (c.refused)
      expect_error([&] { read_fields(f, fields, p); }, Exit::bad_data,
                   {path, c.channel, c.why, "pixel (2, 7)"});
    else
      EXPECT_NO_THROW(read_fields(f, fields, p));
  }
}

TEST_F(ExrFrame, BackgroundDepthIsAccepted) {
  const std::string path = file("bg.exr");
  const auto channels = blender_channels("ViewLayer");
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    if (channels[c] == "ViewLayer.Depth.Z" && y == 0) return 1e10f;
    return value_for(channels[c], x, y);
  });
  const Params p;
  const InputFrame f = open_frame(path, 1, p);
  const GBuffer g = read_fields(f, fields_needed(f, p), p);
  EXPECT_EQ(g.depth[3], 1e10f);
}

TEST_F(ExrFrame, ReadsOnlyTheNeededFields) {
  const std::string path = file("frame_0001.exr");
  write_gbuffer(path, blender_channels("ViewLayer"));
  test::write_sidecar(file("frame_0001.camera.json"), kW, kH);
  const Params p;
  const InputFrame f = open_frame(path, 1, p);
  ASSERT_TRUE(f.has("position"));
  const auto need = fields_needed(f, p);
  EXPECT_EQ(need, (std::vector<std::string>{"depth", "normal", "alpha"}));
  GBuffer g = read_fields(f, need, p);
  EXPECT_EQ(g.width, kW);
  EXPECT_EQ(g.height, kH);
  EXPECT_EQ(g.depth.size(), g.pixels());
  EXPECT_EQ(g.normal.size(), g.pixels());
  EXPECT_EQ(g.alpha.size(), g.pixels());
  EXPECT_TRUE(g.position.empty());
  EXPECT_EQ(g.depth[size_t(3) * kW + 4], depth_at(4, 3));
  EXPECT_EQ(g.normal[size_t(5) * kW + 7].x, normal_at(7, 5).x);
  EXPECT_EQ(g.normal[size_t(5) * kW + 7].z, normal_at(7, 5).z);
  EXPECT_EQ(g.alpha[size_t(2) * kW + kW - 1], 0.5f);

  const Camera cam = find_camera(f, g, p);
  EXPECT_TRUE(contains(cam.source, "sidecar frame_0001.camera.json")) << cam.source;
  EXPECT_EQ(cam.width, kW);
  EXPECT_EQ(cam.height, kH);
  EXPECT_TRUE(g.position.empty()) << "a sidecar camera must not read Position";

  // Without an alpha mapping, alpha is neither resolved nor read.
  Params no_alpha = p;
  no_alpha.passes.erase("alpha");
  const InputFrame f2 = open_frame(path, 1, no_alpha);
  EXPECT_EQ(fields_needed(f2, no_alpha), (std::vector<std::string>{"depth", "normal"}));
}

// Emit is light for the gather only where the frame's direct light lacks the emitters'
// (Params::emission): "auto" takes it from the header, gathered for a frame hbil
// import-povray wrote, direct (not gathered) for any other, as for Cycles' renders.
TEST_F(ExrFrame, EmissionIsGatheredForPovRayImportsUnlessThePresetSays) {
  const std::vector<std::string> channels = blender_channels("ViewLayer");
  test::Pixels px;
  px.spec = OIIO::ImageSpec(kW, kH, int(channels.size()), OIIO::TypeDesc::FLOAT);
  px.spec.channelnames = channels;
  px.data.resize(size_t(kW) * kH * channels.size());
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < int(channels.size()); ++c) px.at(x, y, c) = value_for(channels[c], x, y);
  ASSERT_NO_FATAL_FAILURE(test::write_pixels(file("render.exr"), px));
  px.spec.attribute("hbil:source", "POV-Ray passes in shot/passes (hbil import-povray)");
  ASSERT_NO_FATAL_FAILURE(test::write_pixels(file("import.exr"), px));
  // {emission, gathered for the render, for the import}
  const std::tuple<std::string, bool, bool> cases[] = {
      {"auto", false, true}, {"direct", false, false}, {"gathered", true, true}};
  for (const auto& [emission, render, import] : cases) {
    SCOPED_TRACE(emission);
    Params p;
    p.emission = emission;
    EXPECT_EQ(emission_gathered(open_frame(file("render.exr"), 1, p), p), render);
    const GBuffer g = read_fields(open_frame(file("import.exr"), 1, p), {"depth"}, p);
    EXPECT_EQ(g.emit_gathered, import);
  }
}

TEST_F(ExrFrame, SidecarOfAnotherResolutionIsCameraError) {
  const std::string path = file("frame_0001.exr");
  write_gbuffer(path, blender_channels("ViewLayer"));
  test::write_sidecar(file("frame_0001.camera.json"), 2 * kW, 2 * kH);
  const Params p;
  const InputFrame f = open_frame(path, 1, p);
  GBuffer g = read_fields(f, fields_needed(f, p), p);
  expect_error([&] { find_camera(f, g, p); }, Exit::camera, {"frame 1", path, "48x32", "24x16"});
}

TEST_F(ExrFrame, NoCameraSourceSaysWhatToProvide) {
  const std::string path = file("frame_0004.exr");
  write_gbuffer(path, blender_channels("ViewLayer", true, /*position=*/false));
  const Params p;
  const InputFrame f = open_frame(path, 4, p);
  GBuffer g = read_fields(f, fields_needed(f, p), p);
  expect_error([&] { find_camera(f, g, p); }, Exit::camera,
               {"frame 4", path, "no camera", sidecar_path_for(path), "worldToCamera",
                "ViewLayer.Position.X"});
}

TEST_F(ExrFrame, MissingOrUnreadableFileIsInputError) {
  const std::string missing = file("nope_0001.exr");
  expect_error([&] { open_frame(missing, 1, Params{}); }, Exit::input,
               {"frame 1", missing, "not found"});
  const std::string text = file("text_0002.exr");
  test::write_text(text, "this is not an image\n");
  expect_error([&] { open_frame(text, 2, Params{}); }, Exit::input,
               {"frame 2", text, "cannot read"});
}

// Memory follows the file, not the header: a data window patched far beyond what the file
// holds is refused before anything is allocated from it.
TEST_F(ExrFrame, HeaderClaimingMorePixelsThanTheFileHoldsIsInputError) {
  const std::string sample = test::kRoomPoles + "/frame_0001.exr";  // 256x144, zip, 1.2 MB
  const std::string big = file("big_0001.exr"), huge = file("huge_0001.exr");
  test::patch_data_window(sample, big, 12000, 12000);
  test::patch_data_window(sample, huge, 200000, 200000);
  // 12000 x 12000 x 80 bytes is 11.5 GB uncompressed: zip (deflate, at most 1032:1) cannot
  // store it in 1.2 MB.
  expect_error([&] { open_frame(big, 1, Params{}); }, Exit::input,
               {"frame 1", big, "the header claims 12000x12000 pixels", "34 channels",
                "zip compression", "header is damaged"});
  // Beyond hbil's own limit, whatever the file.
  expect_error([&] { open_frame(huge, 1, Params{}); }, Exit::input,
               {"frame 1", huge, "200000x200000", "limit of 268435456"});
  // The unpatched copy opens.
  test::patch_data_window(sample, file("same_0001.exr"), 256, 144);
  EXPECT_EQ(open_frame(file("same_0001.exr"), 1, Params{}).spec.width, 256);
}

TEST(HeaderSize, BoundsFollowTheCompression) {
  OIIO::ImageSpec spec(1000, 1000, 4, OIIO::TypeDesc::FLOAT);  // 16 MB raw
  auto refused = [&](const std::string& compression, size_t bytes) {
    spec.attribute("compression", compression);
    try {
      check_header_size(spec, true, bytes, "f.exr");
      return false;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Exit::input);
      EXPECT_TRUE(contains(e.what(), "f.exr: the header claims 1000x1000 pixels")) << e.what();
      return true;
    }
  };
  // Uncompressed: every byte is stored (plus 16 bytes per scanline of offsets and headers).
  EXPECT_FALSE(refused("none", 16'000'000 + 16'000));
  EXPECT_TRUE(refused("none", 15'999'999));
  // zip: 16 MB / 1032 = 15.5 KB, plus 63 chunks of 16 lines.
  EXPECT_FALSE(refused("zip", 17'000));
  EXPECT_TRUE(refused("zip", 15'000));
  EXPECT_TRUE(refused("rle", 200'000));     // at most 64:1: 250 KB
  EXPECT_FALSE(refused("dwaa:45", 2'000));  // lossy codecs: a loose bound only
  // An unknown compression: only the chunk offsets (8 + 8 bytes per 256 lines at least).
  EXPECT_FALSE(refused("future", 100));
  EXPECT_TRUE(refused("future", 50));
  // Tiles: 8 bytes of offset and 20 of header per tile (16 x 16 tiles of 64 x 64).
  spec.tile_width = spec.tile_height = 64;
  EXPECT_TRUE(refused("future", 256 * 28 - 1));
  EXPECT_FALSE(refused("future", 256 * 28));
  // Not an EXR, or the size unknown: the pixel limit alone.
  EXPECT_NO_THROW(check_header_size(spec, false, 10, "f.tif"));
  EXPECT_NO_THROW(check_header_size(spec, true, 0, "f.exr"));
  const OIIO::ImageSpec wide(65536, 8192, 1, OIIO::TypeDesc::HALF);
  expect_error([&] { check_header_size(wide, false, 0, "w.tif"); }, Exit::input,
               {"w.tif: the header claims 65536x8192 pixels", "limit"});
}

TEST_F(ExrFrame, BackFaceLayerIsReadForTheBitmaskOnly) {
  // Blender writes a second view layer "BackFaces" (samples/blender/backfaces.py); its
  // Depth.Z sorts before ViewLayer's and must not be taken for the main layer.
  const std::string path = file("frame_0003.exr");
  auto channels = blender_channels("ViewLayer");
  channels.push_back("BackFaces.Depth.Z");
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    return channels[c] == "BackFaces.Depth.Z" ? depth_at(x, y) + 0.5f
                                              : value_for(channels[c], x, y);
  });
  Params p;
  const InputFrame f = open_frame(path, 3, p);
  EXPECT_EQ(f.view_layer, "ViewLayer");
  ASSERT_TRUE(f.has("backdepth"));
  EXPECT_EQ(f.spec.channelnames[f.channels.at("backdepth")[0]], "BackFaces.Depth.Z");
  ASSERT_EQ(p.method, "bitmask");
  // (position: the frame has no camera sidecar, so the camera will be solved from it.)
  EXPECT_EQ(fields_needed(f, p),
            (std::vector<std::string>{"depth", "position", "normal", "backdepth", "alpha"}));
  const GBuffer g = read_fields(f, fields_needed(f, p), p);
  ASSERT_EQ(g.backdepth.size(), g.pixels());
  EXPECT_EQ(g.backdepth[3 * kW + 5], depth_at(5, 3) + 0.5f);
  EXPECT_EQ(g.depth[3 * kW + 5], depth_at(5, 3));

  Params horizon = p;
  horizon.method = "horizon";  // thickness means nothing to the horizon method
  EXPECT_EQ(fields_needed(f, horizon),
            (std::vector<std::string>{"depth", "position", "normal", "alpha"}));
  Params off = apply_set(p, "passes.backdepth=\"\"");
  const InputFrame f_off = open_frame(path, 3, off);
  EXPECT_FALSE(f_off.has("backdepth"));
  EXPECT_EQ(f_off.view_layer, "ViewLayer");
}

TEST_F(ExrFrame, FresnelLayersAreReadOnlyWhenMapped) {
  // Blender writes shader AOVs as <layer>.<name>.X (value) and .R/.G/.B/.A (colour).
  const std::string path = file("frame_0004.exr");
  auto channels = blender_channels("ViewLayer");
  for (const char* c :
       {"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B", "ViewLayer.DiffDir.R",
        "ViewLayer.DiffDir.G", "ViewLayer.DiffDir.B", "ViewLayer.Metallic.X", "ViewLayer.F0.R",
        "ViewLayer.F0.G", "ViewLayer.F0.B"})
    channels.push_back(c);
  test::write_exr(path, kW, kH, channels, [&](int x, int y, int c) {
    return channels[c] == "ViewLayer.Metallic.X" ? 0.125f * float(x % 8)
                                                 : value_for(channels[c], x, y);
  });
  Params p;
  p.outputs = {"indirect"};
  auto needs = [&](const Params& q, const std::string& field) {
    const auto n = fields_needed(open_frame(path, 4, q), q);
    return std::find(n.begin(), n.end(), field) != n.end();
  };
  EXPECT_FALSE(needs(p, "f0"));  // default: no Fresnel weight (right for Blender's DiffCol)
  EXPECT_FALSE(needs(p, "metallic"));
  const Params metal = apply_set(p, "passes.metallic=Metallic");
  EXPECT_TRUE(needs(metal, "metallic"));
  const InputFrame f = open_frame(path, 4, metal);
  const GBuffer g = read_fields(f, {"metallic"}, metal);
  ASSERT_EQ(g.metallic.size(), g.pixels());
  EXPECT_EQ(g.metallic[3], 0.375f);
  const Params both = apply_set(metal, "passes.f0=F0");
  EXPECT_TRUE(needs(both, "f0"));  // F0 wins over metallic
  EXPECT_FALSE(needs(both, "metallic"));
  Params ao_only = both;
  ao_only.outputs = {"ao"};
  EXPECT_FALSE(needs(ao_only, "f0"));  // only the outputs that reflect light read it
}

TEST_F(ExrFrame, EscapePassIsReadOnlyWhenMappedAndForTheAutomaticFill) {
  // Blender's AO pass (R = G = B) rendered with a distance beyond the scene: what escapes it.
  const std::string path = file("frame_0002.exr");
  auto channels = blender_channels("ViewLayer");
  for (const char* c : {"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B",
                        "ViewLayer.DiffDir.R", "ViewLayer.DiffDir.G", "ViewLayer.DiffDir.B"})
    channels.push_back(c);
  const auto value = [&](int x, int y, int c) {
    return channels[c] == "ViewLayer.AO.R" ? 0.0625f * float(x % 16) : value_for(channels[c], x, y);
  };
  test::write_exr(path, kW, kH, channels, value);
  Params p;
  p.outputs = {"indirect"};
  auto needs = [&](const Params& q, const std::string& field) {
    const auto n = fields_needed(open_frame(path, 2, q), q);
    return std::find(n.begin(), n.end(), field) != n.end();
  };
  EXPECT_FALSE(needs(p, "escape"));  // off by default: an AO pass is usually a short one
  const Params escape = apply_set(p, "passes.escape=AO");
  EXPECT_TRUE(needs(escape, "escape"));
  const GBuffer g = read_fields(open_frame(path, 2, escape), {"escape"}, escape);
  ASSERT_EQ(g.escape.size(), g.pixels());
  EXPECT_EQ(g.escape[size_t(kW) + 5], 0.3125f);  // AO.R of pixel (5, 1)
  Params fixed = escape;
  fixed.unseen_radiance_auto = false;  // a fixed fill does not read it
  EXPECT_FALSE(needs(fixed, "escape"));
  Params ao_only = escape;
  ao_only.outputs = {"ao"};  // nor do outputs that gather no light
  EXPECT_FALSE(needs(ao_only, "escape"));
  // A non-finite value names the channel and the pixel.
  const std::string bad = file("frame_0003.exr");
  test::write_exr(bad, kW, kH, channels, [&](int x, int y, int c) {
    return channels[c] == "ViewLayer.AO.R" && x == 4 && y == 9 ? std::nanf("") : value(x, y, c);
  });
  expect_error([&] { read_fields(open_frame(bad, 3, escape), {"escape"}, escape); }, Exit::bad_data,
               {bad, "ViewLayer.AO.R", "non-finite escape", "pixel (4, 9)"});
}

TEST_F(ExrFrame, CameraSolvedFromPositionWithoutSidecar) {
  const std::string src = test::kRoomPoles + "/frame_0001.exr";
  if (!fs::exists(src)) GTEST_SKIP() << src << " is absent";
  const std::string path = file("frame_0001.exr");
  fs::copy_file(src, path);
  ASSERT_FALSE(fs::exists(sidecar_path_for(path)));
  const Params p;
  const InputFrame f = open_frame(path, 1, p);
  GBuffer g = read_fields(f, fields_needed(f, p), p);
  // Without a sidecar or camera attributes, Position is read with the other fields (one
  // pass over the file), for the solve.
  ASSERT_EQ(g.position.size(), g.pixels()) << "Position is read for the solve";
  const Camera cam = find_camera(f, g, p);
  EXPECT_TRUE(contains(cam.source, "solved from Position")) << cam.source;
  EXPECT_GT(cam.reprojection_rms_px, 0.0);
  EXPECT_LT(cam.reprojection_rms_px, kSolvedRmsPx);
  const Camera ref = camera_from_sidecar(test::kRoomPoles + "/frame_0001.camera.json");
  EXPECT_NEAR(cam.fx, ref.fx, kSolvedFocalRel * ref.fx);
  EXPECT_NEAR(cam.fy, ref.fy, kSolvedFocalRel * ref.fy);
  EXPECT_NEAR(cam.cx, ref.cx, 1.0);
  EXPECT_NEAR(cam.cy, ref.cy, 1.0);
  const Vec3d c = cam.centre(), rc = ref.centre();
  EXPECT_NEAR(c.x, rc.x, 0.01);
  EXPECT_NEAR(c.y, rc.y, 0.01);
  EXPECT_NEAR(c.z, rc.z, 0.01);
}

// The spec and native pixel bytes (every channel in its own format) of the image at `path`.
void read_native(const std::string& path, OIIO::ImageSpec& spec,
                 std::vector<unsigned char>& native) {
  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in) << OIIO::geterror();
  spec = in->spec();
  native.resize(spec.image_bytes(true));
  ASSERT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeUnknown, native.data()));
}

// Writes `src` again with tiles of `tile` x `tile` pixels, every channel in its own format.
void write_tiled(const std::string& src, const std::string& dst, int tile) {
  OIIO::ImageSpec spec;
  std::vector<unsigned char> native;
  ASSERT_NO_FATAL_FAILURE(read_native(src, spec, native));
  spec.tile_width = spec.tile_height = tile;
  spec.tile_depth = 1;
  auto out = OIIO::ImageOutput::create(dst);
  ASSERT_TRUE(out && out->open(dst, spec)) << OIIO::geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, native.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

// The G-buffer fields of two reads are the same to the bit.
void expect_same_fields(const GBuffer& ga, const GBuffer& gb) {
  ASSERT_EQ(ga.pixels(), gb.pixels());
  EXPECT_EQ(ga.depth, gb.depth);
  EXPECT_EQ(ga.backdepth, gb.backdepth);
  EXPECT_EQ(ga.alpha, gb.alpha);
  EXPECT_EQ(ga.motion, gb.motion);
  ASSERT_EQ(ga.normal.size(), gb.normal.size());
  EXPECT_EQ(0, std::memcmp(ga.normal.data(), gb.normal.data(), ga.normal.size() * sizeof(Vec3)));
  ASSERT_EQ(ga.diffcol.size(), gb.diffcol.size());
  EXPECT_EQ(0, std::memcmp(ga.diffcol.data(), gb.diffcol.data(), ga.diffcol.size() * sizeof(Vec3)));
  EXPECT_FALSE(ga.diffcol.empty());
}

// Every Blender sample's first frame and its tiled twin: the same G-buffer fields to the
// bit, and so the same output pixels in every layer.
TEST(ExrLayouts, TiledFileGivesTheScanlineTwinsPixels) {
  TempDir dir{test::test_name()};
  for (const char* sample : {"room_poles", "courtyard", "room_cut", "room_static"}) {
    const std::string src = test::kSourceDir + "/samples/" + sample + "/frame_0001.exr";
    for (int tile : {32, 64, 7}) {  // 7: partial tiles at every edge of the 256x144 frame
      SCOPED_TRACE(std::string(sample) + ", tiles of " + std::to_string(tile));
      const std::string tiled = dir / ("tiled" + std::to_string(tile) + ".exr");
      write_tiled(src, tiled, tile);
      Params p;
      const InputFrame a = open_frame(src, 1, p), b = open_frame(tiled, 1, p);
      ASSERT_GT(b.spec.tile_width, 0);
      const std::vector<std::string> need = fields_needed(a, p);
      const GBuffer ga = read_fields(a, need, p), gb = read_fields(b, need, p);
      expect_same_fields(ga, gb);
      if (tile != 32) continue;  // outputs once per sample
      Params q = resolve_outputs(a, p);
      q.gather_radius = 2.0;  // fixed values for the "auto" ones: no scene measured here
      q.thickness = 0.3;
      q.gather_thickness = 0.9;
      const Camera cam = camera_from_sidecar(sidecar_path_for(src));
      test::expect_same_layers(compute_ao_frame(ga, cam, q), compute_ao_frame(gb, cam, q),
                               {"ao", "bent", "cone_cos", "irradiance", "indirect", "composite"});
    }
  }
}

// A tiled, mip-mapped twin (levels down to 1x1, the lower ones filled with another value,
// as a texture pipeline writes): its top level is read, with the original's pixels.
TEST(ExrLayouts, MipMappedFileIsReadFromItsTopLevel) {
  TempDir dir{test::test_name()};
  const std::string src = test::kRoomPoles + "/frame_0001.exr";
  const std::string mip = dir / "mip.exr";
  {
    OIIO::ImageSpec spec;
    std::vector<unsigned char> native;
    ASSERT_NO_FATAL_FAILURE(read_native(src, spec, native));
    spec.tile_width = spec.tile_height = 32;
    spec.tile_depth = 1;
    spec.attribute("textureformat", "Plain Texture");  // what makes the EXR writer keep levels
    spec.attribute("openexr:levelmode", 1);            // MIPMAP_LEVELS
    auto out = OIIO::ImageOutput::create(mip);
    ASSERT_TRUE(out && out->supports("mipmap"));
    ASSERT_TRUE(out->open(mip, spec, OIIO::ImageOutput::Create)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, native.data())) << out->geterror();
    int levels = 1;
    for (int w = spec.width, h = spec.height; w > 1 || h > 1; ++levels) {
      w = std::max(1, w / 2), h = std::max(1, h / 2);
      OIIO::ImageSpec level = spec;
      level.width = level.full_width = w;
      level.height = level.full_height = h;
      const std::vector<float> fill(size_t(w) * h * spec.nchannels, 0.125f);
      ASSERT_TRUE(out->open(mip, level, OIIO::ImageOutput::AppendMIPLevel)) << out->geterror();
      ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, fill.data())) << out->geterror();
    }
    ASSERT_TRUE(out->close());
    EXPECT_EQ(levels, 9);  // 256x144 down to 1x1
    auto back = OIIO::ImageInput::open(mip);
    ASSERT_TRUE(back && back->seek_subimage(0, levels - 1)) << "not mip-mapped";
    EXPECT_EQ(back->spec().width, 1);
  }
  Params p;
  const InputFrame a = open_frame(src, 1, p), b = open_frame(mip, 1, p);
  EXPECT_EQ(b.spec.width, a.spec.width);
  const std::vector<std::string> need = fields_needed(a, p);
  expect_same_fields(read_fields(a, need, p), read_fields(b, need, p));
}

// A multi-part file whose first part is a beauty image (Combined RGBA alone), as compositing
// packages write them, and whose second holds the passes: the second is read, with the
// pixels of the single-part original, through both the float and the half-keeping read.
TEST(ExrLayouts, MultiPartFileIsReadFromThePartHoldingThePasses) {
  TempDir dir{test::test_name()};
  const std::string src = test::kRoomPoles + "/frame_0001.exr";
  const std::string multi = dir / "multipart.exr";
  {
    OIIO::ImageSpec passes;
    std::vector<unsigned char> native;
    ASSERT_NO_FATAL_FAILURE(read_native(src, passes, native));
    OIIO::ImageSpec beauty(passes.width, passes.height, 4, OIIO::TypeDesc::HALF);
    beauty.channelnames = {"R", "G", "B", "A"};
    beauty.alpha_channel = 3;
    const std::vector<float> grey(size_t(passes.width) * passes.height * 4, 0.5f);
    const OIIO::ImageSpec specs[2] = {beauty, passes};
    auto out = OIIO::ImageOutput::create(multi);
    ASSERT_TRUE(out && out->supports("multiimage"));
    ASSERT_TRUE(out->open(multi, 2, specs)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, grey.data())) << out->geterror();
    ASSERT_TRUE(out->open(multi, passes, OIIO::ImageOutput::AppendSubimage)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeUnknown, native.data())) << out->geterror();
    ASSERT_TRUE(out->close());
  }
  Params p;
  const InputFrame a = open_frame(src, 1, p), b = open_frame(multi, 1, p);
  EXPECT_EQ(a.part, 0);
  EXPECT_EQ(b.part, 1);
  EXPECT_EQ(b.channels, a.channels);
  const std::vector<std::string> need = fields_needed(a, p);
  expect_same_fields(read_fields(a, need, p), read_fields(b, need, p));
  GBuffer ha = read_fields(a, need, p, true), hb = read_fields(b, need, p, true);
  ha.unpack();
  hb.unpack();
  expect_same_fields(ha, hb);
}

// OpenEXR sizes an attribute's buffer from the size its header claims before reading it: a
// claim beyond the end of the file is refused first (exit 3, naming the file and attribute).
// Found by tests/fuzz/fuzz_povray: a 23 KB file made OpenEXR fill 2 GB.
TEST(ExrLayouts, AttributeClaimingMoreThanTheFileIsRefusedBeforeReading) {
  TempDir dir{test::test_name()};
  std::ifstream in(test::kRoomPoles + "/frame_0001.exr", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The first attribute after the version: name, type, then its 4-byte size.
  size_t at = 8;
  at = bytes.find('\0', at) + 1;
  at = bytes.find('\0', at) + 1;
  const std::string name = bytes.substr(8, bytes.find('\0', 8) - 8);
  bytes[at] = char(0x00), bytes[at + 1] = char(0x00), bytes[at + 2] = char(0x00),
  bytes[at + 3] = char(0x70);  // 0x70000000: 1.9 GB
  const std::string damaged = dir / "damaged.exr";
  std::ofstream(damaged, std::ios::binary) << bytes;
  expect_error([&] { open_frame(damaged, 1, Params{}); }, Exit::input,
               {damaged, "damaged OpenEXR header", "\"" + name + "\"", "1879048192 bytes"});
}

// Colour fields kept as half (read_fields with keep_half, what `hbil run` does): the packed
// bits unpack to the floats a plain read gives, through both readers (the ZIP reader on the
// sample, OpenEXR's on its tiled twin); geometry fields and float channels stay floats.
TEST(ExrLayouts, HalfColourFieldsUnpackToThePlainReadsFloats) {
  TempDir dir{test::test_name()};
  const std::string src = test::kRoomPoles + "/frame_0001.exr";
  const std::string tiled = dir / "tiled.exr";
  write_tiled(src, tiled, 32);
  for (const std::string& path : {src, tiled}) {
    SCOPED_TRACE(path);
    Params p;
    const InputFrame f = open_frame(path, 1, p);
    const std::vector<std::string> need = fields_needed(f, p);
    const GBuffer plain = read_fields(f, need, p);
    GBuffer packed = read_fields(f, need, p, true);
    std::vector<std::string> names;
    for (const auto& [field, bits] : packed.packed) {
      names.push_back(field);
      EXPECT_EQ(bits.size(), 3 * packed.pixels()) << field;
      EXPECT_TRUE(packed.rgb(field)->empty()) << field << ": no float copy until unpacked";
    }
    EXPECT_EQ(names, (std::vector<std::string>{"diffcol", "diffdir", "emit", "env"}));
    EXPECT_TRUE(packed.has("diffcol") && packed.has("env") && !packed.has("glosscol"));
    EXPECT_FALSE(packed.normal.empty());  // geometry is never packed
    EXPECT_EQ(plain.depth, packed.depth);
    packed.unpack();
    EXPECT_TRUE(packed.packed.empty());
    for (const std::string field : {"diffcol", "diffdir", "emit", "env"}) {
      const std::vector<Vec3>& a = *const_cast<GBuffer&>(plain).rgb(field);
      const std::vector<Vec3>& b = *packed.rgb(field);
      ASSERT_EQ(a.size(), b.size()) << field;
      EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3))) << field;
    }
  }
}

std::vector<std::string> with_diffuse_passes(std::vector<std::string> c) {
  for (const char* pass : {"DiffCol", "DiffDir"})
    for (const char* k : {".R", ".G", ".B"}) c.push_back(std::string("ViewLayer.") + pass + k);
  return c;
}

TEST_F(ExrFrame, FloatColourChannelsAreNotPacked) {
  const std::string path = file("frame_0012.exr");
  const std::vector<std::string> channels = with_diffuse_passes(blender_channels("ViewLayer"));
  write_gbuffer(path, channels);  // every channel 32-bit float
  Params p;
  const InputFrame f = open_frame(path, 12, p);
  const GBuffer g = read_fields(f, fields_needed(f, p), p, true);
  EXPECT_TRUE(g.packed.empty());
  ASSERT_EQ(g.diffcol.size(), g.pixels());
  EXPECT_EQ(g.diffcol[5].x, 0.25f);
}

TEST_F(ExrFrame, NonFiniteHalfColourIsBadData) {
  const std::string path = file("frame_0013.exr");
  const std::vector<std::string> channels = with_diffuse_passes(blender_channels("ViewLayer"));
  test::Pixels px;
  px.spec = OIIO::ImageSpec(kW, kH, int(channels.size()), OIIO::TypeDesc::FLOAT);
  px.spec.channelnames = channels;
  for (const std::string& c : channels)
    px.spec.channelformats.push_back(c.find("Diff") != std::string::npos ? OIIO::TypeDesc::HALF
                                                                         : OIIO::TypeDesc::FLOAT);
  px.data.resize(size_t(kW) * kH * channels.size());
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < int(channels.size()); ++c)
        px.at(x, y, c) = channels[c] == "ViewLayer.DiffDir.G" && x == 3 && y == 2
                             ? std::numeric_limits<float>::quiet_NaN()
                             : value_for(channels[c], x, y);
  test::write_pixels(path, px);
  Params p;
  const InputFrame f = open_frame(path, 13, p);
  const std::vector<std::string> need = fields_needed(f, p);
  for (bool keep_half : {false, true}) {
    SCOPED_TRACE(keep_half);
    expect_error([&] { read_fields(f, need, p, keep_half); }, Exit::bad_data,
                 {"frame 13", path, "ViewLayer.DiffDir.G", "pixel (3, 2)", "nan"});
  }
}

}  // namespace
}  // namespace hbil::io
