// test_util.h: helpers shared by the I/O and command-line tests: per-test temporary
// folders, error expectations, small EXR writers and readers, and running the hbil binary.
//
// Every test that touches files works in its own folder
// temp_directory_path()/hbil-test-<pid>-<name>, removed when the test ends, so the suite
// may run in parallel (ctest -j) and leaves nothing behind.
#pragma once

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hbil/ao_frame.h"
#include "hbil/error.h"

namespace hbil::test {

namespace fs = std::filesystem;

inline const std::string kSourceDir = HBIL_SOURCE_DIR;
inline const std::string kRoomPoles = kSourceDir + "/samples/room_poles";

// A fresh, empty folder for one test, removed (with its contents) on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(fs::temp_directory_path() / ("hbil-test-" + std::to_string(getpid()) + "-" + name)) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    // An unwritable folder made by a test must not keep its contents from being removed.
    for (auto it = fs::recursive_directory_iterator(path_, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
      if (it->is_directory(ec))
        fs::permissions(it->path(), fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }
  std::string operator/(const std::string& rel) const { return (path_ / rel).string(); }

 private:
  fs::path path_;
};

// The name of the running test, usable in a file name: "Suite_Name".
// Two computed layers hold the same bytes (and were computed: not empty).
template <class V>
void expect_same_bytes(const V& a, const V& b, const char* layer) {
  ASSERT_EQ(a.size(), b.size()) << layer;
  ASSERT_FALSE(a.empty()) << layer << " was not computed";
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0]))) << layer;
}

// Two computed frames hold the same bytes in every layer either holds, and each layer of
// `computed` (ao, ao_rgb, bent, cone_cos, irradiance, indirect, composite, farfield) was
// computed.
inline void expect_same_layers(const AoFrame& a, const AoFrame& b,
                               std::initializer_list<std::string> computed) {
  auto check = [&](const char* name, const auto& x, const auto& y) {
    const bool wanted = std::find(computed.begin(), computed.end(), name) != computed.end();
    if (wanted || !x.empty() || !y.empty()) expect_same_bytes(x, y, name);
  };
  check("ao", a.ao, b.ao);
  check("ao_rgb", a.ao_rgb, b.ao_rgb);
  check("bent", a.bent, b.bent);
  check("cone_cos", a.cone_cos, b.cone_cos);
  check("irradiance", a.irradiance, b.irradiance);
  check("indirect", a.indirect, b.indirect);
  check("composite", a.composite, b.composite);
  check("farfield", a.farfield, b.farfield);
}

inline std::string test_name() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string s = std::string(info->test_suite_name()) + "_" + info->name();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

inline bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// Runs f, expects hbil::Error with `code` and a message containing every needle.
template <typename F>
void expect_error(F&& f, Exit code, std::initializer_list<std::string> needles) {
  try {
    f();
    ADD_FAILURE() << "no exception (expected exit code " << int(code) << ")";
  } catch (const Error& e) {
    EXPECT_EQ(int(e.code()), int(code)) << e.what();
    for (const auto& n : needles)
      EXPECT_TRUE(contains(e.what(), n)) << "message \"" << e.what() << "\" lacks \"" << n << "\"";
  }
}

inline std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << p;
}

// Files whose name contains `part`, anywhere below `dir`.
inline std::vector<std::string> files_containing(const fs::path& dir, const std::string& part) {
  std::vector<std::string> out;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    if (contains(it->path().filename().string(), part)) out.push_back(it->path().string());
  return out;
}

// ---------------------------------------------------------------------------------------
// EXR files

// A whole image as 32-bit float, all channels interleaved, plus its header.
struct Pixels {
  OIIO::ImageSpec spec;
  std::vector<float> data;

  int channel(const std::string& name) const {
    for (int c = 0; c < spec.nchannels; ++c)
      if (spec.channelnames[c] == name) return c;
    return -1;
  }
  float& at(int x, int y, int c) { return data[(size_t(y) * spec.width + x) * spec.nchannels + c]; }
  float at(int x, int y, int c) const {
    return data[(size_t(y) * spec.width + x) * spec.nchannels + c];
  }
};

inline Pixels read_pixels(const std::string& path) {
  Pixels p;
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    ADD_FAILURE() << "cannot open " << path << ": " << OIIO::geterror();
    return p;
  }
  p.spec = in->spec();
  p.data.resize(size_t(p.spec.width) * p.spec.height * p.spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, p.spec.nchannels, OIIO::TypeDesc::FLOAT, p.data.data()))
      << in->geterror();
  return p;
}

// Writes a float EXR (ZIP) with the header's attributes and the given pixels.
inline void write_pixels(const std::string& path, const Pixels& p) {
  OIIO::ImageSpec spec = p.spec;
  spec.set_format(OIIO::TypeDesc::FLOAT);
  spec.channelformats.clear();
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  spec.attribute("compression", "zip");
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, p.data.data())) << out->geterror();
  ASSERT_TRUE(out->close()) << out->geterror();
}

// A synthetic image: channel names and a value for (x, y, channel index).
inline void write_exr(const std::string& path, int w, int h,
                      const std::vector<std::string>& channels,
                      const std::function<float(int, int, int)>& value) {
  Pixels p;
  p.spec = OIIO::ImageSpec(w, h, int(channels.size()), OIIO::TypeDesc::FLOAT);
  p.spec.channelnames = channels;
  p.data.resize(size_t(w) * h * channels.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < int(channels.size()); ++c) p.at(x, y, c) = value(x, y, c);
  write_pixels(path, p);
}

// A copy of `src` without the channels whose name starts with any of `drop`, after
// `edit` has changed the pixels (channel indices are those of the copy).
inline void copy_exr(const std::string& src, const std::string& dst,
                     const std::vector<std::string>& drop = {},
                     const std::function<void(Pixels&)>& edit = {}) {
  const Pixels in = read_pixels(src);
  std::vector<int> keep;
  for (int c = 0; c < in.spec.nchannels; ++c) {
    bool dropped = false;
    for (const auto& d : drop) dropped |= in.spec.channelnames[c].rfind(d, 0) == 0;
    if (!dropped) keep.push_back(c);
  }
  Pixels out;
  out.spec = in.spec;
  out.spec.nchannels = int(keep.size());
  out.spec.channelnames.clear();
  for (int c : keep) out.spec.channelnames.push_back(in.spec.channelnames[c]);
  out.data.resize(size_t(in.spec.width) * in.spec.height * keep.size());
  for (int y = 0; y < in.spec.height; ++y)
    for (int x = 0; x < in.spec.width; ++x)
      for (size_t k = 0; k < keep.size(); ++k) out.at(x, y, int(k)) = in.at(x, y, keep[k]);
  if (edit) edit(out);
  write_pixels(dst, out);
}

// A top-left crop of `src` to w x h, all channels.
inline void crop_exr(const std::string& src, const std::string& dst, int w, int h) {
  const Pixels in = read_pixels(src);
  Pixels out;
  out.spec = in.spec;
  out.spec.width = out.spec.full_width = w;
  out.spec.height = out.spec.full_height = h;
  out.data.resize(size_t(w) * h * in.spec.nchannels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < in.spec.nchannels; ++c) out.at(x, y, c) = in.at(x, y, c);
  write_pixels(dst, out);
}

// The w x h pixels of `src` from (x0, y0), all channels, written as a float EXR whose data
// window is at (x0, y0) and whose display window is src's (`keep_window`: a crop as a
// compositor writes it), or as an image of its own with both windows at (0, 0).
inline void window_exr(const std::string& src, const std::string& dst, int x0, int y0, int w, int h,
                       bool keep_window) {
  const Pixels in = read_pixels(src);
  Pixels out;
  out.spec = in.spec;
  out.spec.width = w;
  out.spec.height = h;
  out.spec.x = keep_window ? x0 : 0;
  out.spec.y = keep_window ? y0 : 0;
  if (!keep_window) {
    out.spec.full_x = out.spec.full_y = 0;
    out.spec.full_width = w;
    out.spec.full_height = h;
  }
  out.data.resize(size_t(w) * h * in.spec.nchannels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < in.spec.nchannels; ++c) out.at(x, y, c) = in.at(x0 + x, y0 + y, c);
  write_pixels(dst, out);
}

// A copy of the OpenEXR file `src` whose header's displayWindow is w x h pixels from (x, y);
// the pixels and the data window stay as they are.
inline void patch_display_window(const std::string& src, const std::string& dst, int x, int y,
                                 int w, int h) {
  std::string bytes = read_text(src);
  const std::string key("displayWindow\0box2i\0", 20);
  const size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos) << src << " has no displayWindow attribute";
  const int32_t box[4] = {x, y, x + w - 1, y + h - 1};  // xMin, yMin, xMax, yMax
  ASSERT_EQ(bytes.compare(at + key.size(), 4, std::string("\x10\0\0\0", 4)), 0);
  std::memcpy(&bytes[at + key.size() + 4], box, sizeof box);
  write_text(dst, bytes);
}

// A copy of the OpenEXR file `src` whose header's dataWindow says w x h pixels (from
// (0, 0)); nothing else changes, so the pixels stored no longer match it.
inline void patch_data_window(const std::string& src, const std::string& dst, int w, int h) {
  std::string bytes = read_text(src);
  const std::string key("dataWindow\0box2i\0", 17);
  const size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos) << src << " has no dataWindow attribute";
  const int32_t box[4] = {0, 0, w - 1, h - 1};  // xMin, yMin, xMax, yMax (little-endian)
  ASSERT_EQ(bytes.compare(at + key.size(), 4, std::string("\x10\0\0\0", 4)), 0);
  std::memcpy(&bytes[at + key.size() + 4], box, sizeof box);
  write_text(dst, bytes);
}

// A copy of `src` cut to its first `bytes` bytes.
inline void truncate_copy(const std::string& src, const std::string& dst, size_t bytes) {
  const std::string all = read_text(src);
  ASSERT_LT(bytes, all.size());
  write_text(dst, all.substr(0, bytes));
}

// A camera sidecar: the room_poles frame 1 camera with its resolution replaced.
inline void write_sidecar(const std::string& path, int w, int h) {
  nlohmann::json j = nlohmann::json::parse(read_text(kRoomPoles + "/frame_0001.camera.json"));
  j["resolution"] = {w, h};
  write_text(path, j.dump(2));
}

// ---------------------------------------------------------------------------------------
// The hbil binary

inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Short form for building command lines.
inline std::string q(const std::string& s) {
  return shell_quote(s);
}

struct RunResult {
  int code = -1;  // exit status; -1 when the process did not exit normally
  std::string out, err;
};

// Runs `hbil <args>` (args already quoted where needed) with stdout and stderr captured
// in files of `dir`.
inline RunResult run_hbil(const std::string& args, const fs::path& dir) {
  const fs::path out = dir / ".stdout.txt", err = dir / ".stderr.txt";
  const std::string cmd = shell_quote(HBIL_BINARY) + " " + args + " > " +
                          shell_quote(out.string()) + " 2> " + shell_quote(err.string()) +
                          " < /dev/null";
  const int status = std::system(cmd.c_str());
  RunResult r;
  if (status != -1 && WIFEXITED(status)) r.code = WEXITSTATUS(status);
  r.out = read_text(out);
  r.err = read_text(err);
  fs::remove(out);
  fs::remove(err);
  return r;
}

}  // namespace hbil::test
