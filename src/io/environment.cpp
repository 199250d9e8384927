// environment.cpp: see environment.h.
#include "io/environment.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <vector>

#include "hbil/error.h"
#include "io/header_size.h"

namespace hbil::io {

namespace fs = std::filesystem;

namespace {

constexpr const char* kRgbPrefix = "rgb:";

SH9 parse_constant(const std::string& spec) {
  const std::string body = spec.substr(std::string(kRgbPrefix).size());
  float v[3];
  const char* p = body.data();
  const char* end = body.data() + body.size();
  bool ok = true;
  for (int i = 0; i < 3 && ok; ++i) {
    if (i > 0) {
      ok = p < end && *p == ',';
      ++p;
    }
    if (!ok) break;
    auto [next, ec] = std::from_chars(p, end, v[i]);
    ok = ec == std::errc() && std::isfinite(v[i]) && v[i] >= 0.0f;
    p = next;
  }
  if (!ok || p != end)
    throw Error(Exit::usage, "environment \"" + spec +
                                 "\": expected rgb:R,G,B with three finite numbers >= 0, "
                                 "e.g. rgb:0.1,0.2,0.3");
  return constant_environment(Vec3(v[0], v[1], v[2]));
}

SH9 read_equirect(const std::string& path) {
  const std::string where = "environment " + path;
  if (!fs::exists(path)) throw Error(Exit::input, where + ": file not found");
  auto in = open_image_input(path, where);
  if (!in) throw Error(Exit::input, where + ": cannot read: " + OIIO::geterror());
  const OIIO::ImageSpec spec = in->spec();
  if (spec.deep) throw Error(Exit::input, where + ": deep images are not supported");
  check_header_size(path, spec, std::string(in->format_name()) == "openexr", where);
  if (spec.nchannels < 3) {
    std::ostringstream m;
    m << where << ": " << spec.nchannels << " channel(s); an environment needs R, G, B";
    throw Error(Exit::bad_data, m.str());
  }
  if (spec.width != 2 * spec.height || spec.depth > 1) {
    std::ostringstream m;
    m << where << ": " << spec.width << " x " << spec.height
      << " pixels; an equirectangular map needs width = 2 x height";
    throw Error(Exit::bad_data, m.str());
  }
  // Channels: R, G, B by name, else the first three.
  int ch[3] = {-1, -1, -1};
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < spec.nchannels; ++c)
    for (int k = 0; k < 3; ++k)
      if (spec.channelnames[c] == names[k] && ch[k] < 0) ch[k] = c;
  if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0) ch[0] = 0, ch[1] = 1, ch[2] = 2;
  const int lo = std::min({ch[0], ch[1], ch[2]}), hi = std::max({ch[0], ch[1], ch[2]}) + 1;
  const int n = hi - lo;
  const size_t pixels = size_t(spec.width) * size_t(spec.height);
  std::vector<float> raw(pixels * size_t(n));
  if (!in->read_image(0, 0, lo, hi, OIIO::TypeDesc::FLOAT, raw.data()))
    throw Error(Exit::input, where + ": cannot read pixels: " + in->geterror());
  in->close();
  std::vector<float> rgb(pixels * 3);
  for (size_t i = 0; i < pixels; ++i)
    for (int k = 0; k < 3; ++k) rgb[i * 3 + k] = raw[i * size_t(n) + size_t(ch[k] - lo)];
  raw = {};
  try {
    return project_equirect(rgb.data(), spec.width, spec.height);
  } catch (const Error& e) {
    throw Error(e.code(), where + ": " + e.what());
  }
}

}  // namespace

SH9 load_environment(const std::string& spec) {
  if (spec.rfind(kRgbPrefix, 0) == 0) return parse_constant(spec);
  if (spec.empty()) throw Error(Exit::usage, "environment: empty specification");
  return read_equirect(spec);
}

}  // namespace hbil::io
