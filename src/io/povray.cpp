// povray.cpp: POV-Ray pass folders -> Blender-like G-buffer frames (see povray.h).
#include "io/povray.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "hbil/error.h"
#include "hbil/farfield.h"
#include "io/camera_io.h"
#include "io/header_size.h"

namespace hbil::io {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr float kBackgroundDepth = 1e10f;  // what Blender writes where nothing was hit

Vec3d read_vec(const json& j, const char* key, const std::string& path) {
  const json& v = camera_file_key(j, key, path);
  if (!v.is_array() || v.size() != 3)
    camera_file_error(path, std::string("key \"") + key + "\" must be an array of 3 numbers");
  return {camera_file_number(v[0], key, path), camera_file_number(v[1], key, path),
          camera_file_number(v[2], key, path)};
}

double read_num(const json& j, const char* key, const std::string& path) {
  return camera_file_number(camera_file_key(j, key, path), key, path);
}

// A whole number that an int holds (a larger one would be undefined as an int).
int read_int(const json& j, const char* key, const std::string& path) {
  const double d = read_num(j, key, path);
  if (!(std::abs(d) < 2147483647.0) || d != std::trunc(d))
    camera_file_error(path, std::string("key \"") + key + "\" must be a whole number within " +
                                "+-2147483647, found " + camera_file_key(j, key, path).dump());
  return int(d);
}

// A pass image as float, `min_channels` or more channels. Errors name the file and frame.
struct PassImage {
  int width = 0, height = 0, nchannels = 0;
  std::vector<float> data;
  float at(size_t pixel, int c) const { return data[pixel * nchannels + c]; }
};

PassImage read_pass(const std::string& path, int frame, const std::string& pass, int min_channels,
                    int width, int height) {
  const std::string where = "frame " + std::to_string(frame) + " (" + path + "), " + pass + " pass";
  auto in = open_image_input(path, where);
  if (!in) throw Error(Exit::input, where + ": cannot read: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  check_header_size(path, spec, std::string(in->format_name()) == "openexr", where);
  PassImage img;
  img.width = spec.width;
  img.height = spec.height;
  img.nchannels = spec.nchannels;
  if (img.width != width || img.height != height)
    throw Error(Exit::bad_data, where + ": " + std::to_string(img.width) + "x" +
                                    std::to_string(img.height) + " pixels, the camera file says " +
                                    std::to_string(width) + "x" + std::to_string(height));
  if (img.nchannels < min_channels)
    throw Error(Exit::missing_pass, where + ": " + std::to_string(img.nchannels) +
                                        " channels, needs " + std::to_string(min_channels) +
                                        (min_channels == 4 ? " (render it with +UA)" : ""));
  img.data.resize(size_t(width) * height * img.nchannels);
  if (!in->read_image(0, 0, 0, img.nchannels, OIIO::TypeDesc::FLOAT, img.data.data()))
    throw Error(Exit::input, where + ": cannot read pixels: " + in->geterror());
  for (float v : img.data)
    if (!std::isfinite(v))
      throw Error(Exit::bad_data, where + ": holds a non-finite value (" + std::to_string(v) + ")");
  return img;
}

}  // namespace

PovrayCamera read_povray_camera(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(Exit::input, path + ": cannot read the camera file");
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    camera_file_error(path, std::string("not valid JSON: ") + e.what());
  }
  // (A key given twice keeps its last value, of any type: compared as JSON, not read as a string.)
  if (!j.is_object() || !j.contains("format") || j["format"] != "hbil-povray-camera-1")
    camera_file_error(path, "key \"format\" must be \"hbil-povray-camera-1\"");
  PovrayCamera c;
  c.frame = read_int(j, "frame", path);
  c.clock = read_num(j, "clock", path);
  c.width = read_int(j, "width", path);
  c.height = read_int(j, "height", path);
  c.depth_range = read_num(j, "depth_range", path);
  c.location = read_vec(j, "location", path);
  c.direction = read_vec(j, "direction", path);
  c.right = read_vec(j, "right", path);
  c.up = read_vec(j, "up", path);
  if (c.width <= 0 || c.height <= 0)
    camera_file_error(path, "keys \"width\" and \"height\" must be > 0");
  if (j.contains("guard")) {
    const json& g = j["guard"];
    if (!g.is_array() || g.size() != 2 || !g[0].is_number_integer() || !g[1].is_number_integer() ||
        g[0].get<long long>() < 0 || g[1].get<long long>() < 0 ||
        2 * g[0].get<long long>() >= c.width || 2 * g[1].get<long long>() >= c.height)
      camera_file_error(path,
                        "key \"guard\" must be [x, y], integers >= 0 that leave a frame inside "
                        "the width and height, found " +
                            g.dump());
    c.guard_x = g[0].get<int>();
    c.guard_y = g[1].get<int>();
  }
  if (j.contains("panorama")) {
    if (!j["panorama"].is_boolean())
      camera_file_error(path,
                        "key \"panorama\" must be true or false, found " + j["panorama"].dump());
    c.panorama = j["panorama"].get<bool>();
    if (c.panorama && (c.guard_x > 0 || c.guard_y > 0))
      camera_file_error(path, "a panorama has no guard band (keys \"panorama\" and \"guard\")");
  }
  if (!(c.depth_range > 0)) camera_file_error(path, "key \"depth_range\" must be > 0");
  // Squared (as lengths are) without overflowing a double: the camera centre stays finite.
  if (!std::isfinite(dot(c.location, c.location)))
    camera_file_error(path, "key \"location\" is out of range");
  const double ld = length(c.direction), lr = length(c.right), lu = length(c.up);
  if (!(ld > 0 && lr > 0 && lu > 0))
    camera_file_error(path, "\"direction\", \"right\" and \"up\" must not be zero");
  // Their lengths and the focal lengths they make must be finite and not vanish.
  const double fx = c.width * ld / lr, fy = c.height * ld / lu;
  if (!(std::isfinite(ld * lr * lu) && std::isfinite(fx) && std::isfinite(fy) && fx > 1e-12 &&
        fy > 1e-12))
    camera_file_error(path,
                      "\"direction\", \"right\" and \"up\" have lengths out of range (a focal "
                      "length of " +
                          std::to_string(fx) + " pixels)");
  const double tol = 1e-6;
  if (std::abs(dot(c.direction, c.right)) > tol * ld * lr ||
      std::abs(dot(c.direction, c.up)) > tol * ld * lu ||
      std::abs(dot(c.right, c.up)) > tol * lr * lu)
    camera_file_error(path, "\"direction\", \"right\" and \"up\" are not orthogonal");
  // Square pixels: |right| / |up| = width / height.
  if (std::abs(lr / lu - double(c.width) / c.height) > 1e-6 * lr / lu)
    camera_file_error(path, "|right| / |up| is not width / height (pixels are not square)");
  // POV-Ray draws +right to the right of the image and +up upwards when (right, up,
  // direction) is left-handed in its space, which hbil.inc's cameras are.
  if (dot(cross(c.right, c.up), c.direction) <= 0)
    camera_file_error(path, "right x up does not point along direction (a mirrored camera)");
  return c;
}

Camera camera_from_povray(const PovrayCamera& c, const std::string& source) {
  Camera cam;
  cam.width = c.width;
  cam.height = c.height;
  const double ld = length(c.direction), lr = length(c.right), lu = length(c.up);
  cam.fx = c.width * ld / lr;
  cam.fy = c.height * ld / lu;
  cam.cx = 0.5 * c.width;
  cam.cy = 0.5 * c.height;
  // View axes (+x right, +y down, +z forward) as world directions.
  const Vec3d ax = pov_to_world(c.right / lr), ay = pov_to_world(-(c.up / lu)),
              az = pov_to_world(c.direction / ld);
  const Vec3d rows[3] = {ax, ay, az};
  for (int i = 0; i < 3; ++i) {
    cam.R.m[i][0] = rows[i].x;
    cam.R.m[i][1] = rows[i].y;
    cam.R.m[i][2] = rows[i].z;
  }
  cam.t = -(cam.R * pov_to_world(c.location));
  cam.source = source;
  return cam;
}

double decode_povray_depth(float r, float g, float b, double range) {
  const double coarse = std::round(double(r) * 2048), middle = std::round(double(g) * 2048);
  return (coarse + (middle + double(b)) / 2048) / 2048 * range;
}

Vec3 decode_povray_normal(float sx, float sy, float sz) {
  constexpr double kPi = 3.14159265358979323846;
  // slope value s = 1 - angle / pi, so the component is cos(pi (1 - s)) = -cos(pi s).
  const Vec3d pov(-std::cos(kPi * sx), -std::cos(kPi * sy), -std::cos(kPi * sz));
  const double l = length(pov);
  if (!(l > 0.5 && l < 1.5)) return {};
  return Vec3(pov_to_world(pov / l));
}

namespace {

// Calls fn(pass or "camera", frame, path) for every pass or camera file in `dir`.
template <typename Fn>
void scan_pass_folder(const std::string& dir, Fn fn) {
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec) throw Error(Exit::input, dir + ": cannot read the pass folder: " + ec.message());
  static const std::regex re(
      "(depth|normal|albedo|emit|direct|backfaces|reference)([0-9]{0,9})\\.exr|"
      "camera([0-9]{0,9})\\.json");
  for (const auto& entry : it) {
    const std::string name = entry.path().filename().string();
    std::smatch m;
    if (!std::regex_match(name, m, re)) continue;
    const bool camera = m[1].length() == 0;
    const std::string digits = camera ? m[3].str() : m[2].str();
    fn(camera ? std::string("camera") : m[1].str(), digits.empty() ? 0 : std::stoi(digits),
       entry.path().string());
  }
}

}  // namespace

std::vector<PovrayFrameFiles> find_povray_frames(const std::string& dir,
                                                 const std::string& reference_dir) {
  std::map<int, PovrayFrameFiles> frames;
  scan_pass_folder(dir, [&](const std::string& pass, int f, const std::string& path) {
    frames[f].frame = f;
    if (pass == "camera")
      frames[f].camera = path;
    else if (reference_dir.empty() || pass != "reference")
      frames[f].passes[pass] = path;
  });
  if (!reference_dir.empty())
    scan_pass_folder(reference_dir, [&](const std::string& pass, int f, const std::string& path) {
      if (pass == "reference" && frames.count(f)) frames[f].passes[pass] = path;
    });
  std::vector<PovrayFrameFiles> out;
  for (auto& [f, files] : frames)
    if (files.passes.count("depth")) out.push_back(std::move(files));
  if (out.empty())
    throw Error(Exit::input, dir +
                                 ": no depth<frame>.exr in the folder (render_gbuffer.sh "
                                 "writes depth, normal, ... and camera<frame>.json there)");
  return out;
}

ImportedFrame import_povray_frame(const PovrayFrameFiles& files, const std::string& view_layer) {
  const int frame = files.frame;
  const std::string where_frame = "frame " + std::to_string(frame);
  if (files.camera.empty())
    throw Error(Exit::camera, where_frame + " (" + files.passes.at("depth") + "): no camera" +
                                  std::to_string(frame) +
                                  ".json beside it (hbil.inc writes it in the depth pass)");
  const PovrayCamera pc = read_povray_camera(files.camera);
  if (!pc.panorama && !files.passes.count("normal"))
    throw Error(Exit::missing_pass, where_frame + " (" + files.passes.at("depth") + "): no normal" +
                                        std::to_string(frame) +
                                        ".exr beside it (pass 2 of render_gbuffer.sh)");
  const int w = pc.width, h = pc.height;
  const size_t n = size_t(w) * h;

  ImportedFrame out;
  out.width = w;
  out.height = h;
  out.guard_x = pc.guard_x;
  out.guard_y = pc.guard_y;
  out.panorama = pc.panorama;
  if (!pc.panorama)
    out.camera = camera_from_povray(pc, "POV-Ray " + fs::path(files.camera).filename().string());

  auto read = [&](const std::string& pass, int min_channels) {
    return read_pass(files.passes.at(pass), frame, pass, min_channels, w, h);
  };
  const PassImage depth = read("depth", 4);

  // Each layer as planar float data first; interleaved at the end.
  std::deque<std::pair<std::string, std::vector<float>>> planes;  // references stay valid
  auto add = [&](const std::string& name) -> std::vector<float>& {
    planes.emplace_back(name, std::vector<float>(n, 0.0f));
    return planes.back().second;
  };
  const std::string L = view_layer.empty() ? "" : view_layer + ".";

  // A decoded depth as float. Digits far outside [0, 1] or a huge depth_range could decode
  // beyond float's range: bad data, naming the pass and pixel.
  auto decoded_depth = [&](const PassImage& img, size_t i, const std::string& pass) {
    const double d = decode_povray_depth(img.at(i, 0), img.at(i, 1), img.at(i, 2), pc.depth_range);
    if (!std::isfinite(float(d)))
      throw Error(Exit::bad_data, where_frame + " (" + files.passes.at(pass) + "), " + pass +
                                      " pass: pixel (" + std::to_string(i % w) + ", " +
                                      std::to_string(i / w) + ") decodes to a depth of " +
                                      std::to_string(d) + ", beyond a float (depth_range " +
                                      std::to_string(pc.depth_range) + ")");
    return float(d);
  };
  std::vector<float> z(n), alpha(n);
  std::vector<bool> hit(n);
  for (size_t i = 0; i < n; ++i) {
    // Depth 0 is no surface either: a scene's own opaque background{} hides the alpha.
    hit[i] =
        depth.at(i, 3) >= 0.5f && (depth.at(i, 0) > 0 || depth.at(i, 1) > 0 || depth.at(i, 2) > 0);
    alpha[i] = hit[i] ? 1.0f : 0.0f;
    z[i] = hit[i] ? decoded_depth(depth, i, "depth") : kBackgroundDepth;
  }
  add(L + "Depth.Z") = z;
  out.layers.push_back("Depth");
  if (pc.panorama) {
    // Where each pixel looks: the equirectangular directions of `environment`
    // (equirect_to_direction), from the camera's location in hbil's world.
    auto& px = add(L + "Position.X");
    auto& py = add(L + "Position.Y");
    auto& pz = add(L + "Position.Z");
    const Vec3d o = pov_to_world(pc.location);
    for (int row = 0; row < h; ++row)
      for (int col = 0; col < w; ++col) {
        const size_t i = size_t(row) * w + col;
        if (!hit[i]) continue;
        const Vec3d d = equirect_to_direction((col + 0.5) / w, 1.0 - (row + 0.5) / h);
        const Vec3d p = o + d * double(z[i]);
        px[i] = float(p.x);
        py[i] = float(p.y);
        pz[i] = float(p.z);
        if (!std::isfinite(px[i]) || !std::isfinite(py[i]) || !std::isfinite(pz[i]))
          throw Error(Exit::bad_data, where_frame + " (" + files.camera + "): pixel (" +
                                          std::to_string(col) + ", " + std::to_string(row) +
                                          ") of the panorama lies beyond a float (its location "
                                          "plus its distance)");
      }
    out.layers.push_back("Position");
  } else {
    const PassImage normal = read("normal", 3);
    auto& nx = add(L + "Normal.X");
    auto& ny = add(L + "Normal.Y");
    auto& nz = add(L + "Normal.Z");
    const Vec3d centre = out.camera.centre();
    for (int row = 0; row < h; ++row)
      for (int col = 0; col < w; ++col) {
        const size_t i = size_t(row) * w + col;
        if (!hit[i]) continue;
        Vec3 nn = decode_povray_normal(normal.at(i, 0), normal.at(i, 1), normal.at(i, 2));
        // Towards the camera, as Cycles' Normal pass is (it flips back faces).
        const Vec3d p = out.camera.view_to_world(out.camera.unproject(col + 0.5, row + 0.5, z[i]));
        if (dot(Vec3d(nn), p - centre) > 0) nn = -nn;
        nx[i] = nn.x;
        ny[i] = nn.y;
        nz[i] = nn.z;
      }
    out.layers.push_back("Normal");
  }

  auto add_rgb = [&](const std::string& pass, const PassImage& img, bool where_hit,
                     bool where_background) {
    auto& r = add(L + pass + ".R");
    auto& g = add(L + pass + ".G");
    auto& b = add(L + pass + ".B");
    for (size_t i = 0; i < n; ++i) {
      if (!(hit[i] ? where_hit : where_background)) continue;
      r[i] = img.at(i, 0);
      g[i] = img.at(i, 1);
      b[i] = img.at(i, 2);
    }
    out.layers.push_back(pass);
  };
  // The optional colour passes (empty when absent).
  auto optional = [&](const std::string& pass) {
    return files.passes.count(pass) ? read(pass, 3) : PassImage{};
  };
  const PassImage albedo = optional("albedo"), direct = optional("direct"), emit = optional("emit"),
                  ref = optional("reference");
  if (!albedo.data.empty()) add_rgb("DiffCol", albedo, true, false);
  if (!direct.data.empty()) add_rgb("DiffDir", direct, true, false);
  if (!emit.data.empty()) {
    add_rgb("Emit", emit, true, false);
    add_rgb("Env", emit, false, true);
  }
  if (!ref.data.empty()) {
    add_rgb("Combined", ref, true, true);
    out.layers.back() = "Combined (reference)";
  }
  add(L + "Combined.A") = alpha;
  if (!ref.data.empty() && !albedo.data.empty() && !direct.data.empty() && !emit.data.empty()) {
    // Cycles' DiffInd is the indirect diffuse light divided by DiffCol.
    std::vector<float>* ch[3] = {&add(L + "DiffInd.R"), &add(L + "DiffInd.G"),
                                 &add(L + "DiffInd.B")};
    for (size_t i = 0; i < n; ++i) {
      if (!hit[i]) continue;
      for (int c = 0; c < 3; ++c) {
        const float col = albedo.at(i, c);
        if (!(col > 0)) continue;
        // In double: float could overflow here. Where it still does, the diffuse colour is
        // too small to divide by, as where it is 0.
        const double indirect =
            double(ref.at(i, c)) - double(col) * direct.at(i, c) - emit.at(i, c);
        const float v = float(std::max(indirect, 0.0) / col);
        if (std::isfinite(v)) (*ch[c])[i] = v;
      }
    }
    out.layers.push_back("DiffInd");
  }
  if (files.passes.count("backfaces")) {
    const PassImage img = read("backfaces", 3);
    auto& zb = add("BackFaces.Depth.Z");
    for (size_t i = 0; i < n; ++i) {
      const float d = hit[i] ? decoded_depth(img, i, "backfaces") : 0.0f;
      zb[i] = d > 0 ? d : kBackgroundDepth;
    }
    out.layers.push_back("BackFaces.Depth");
  }

  out.channels.reserve(planes.size());
  for (const auto& p : planes) out.channels.push_back(p.first);
  const size_t nc = planes.size();
  out.pixels.resize(n * nc);
  for (size_t c = 0; c < nc; ++c)
    for (size_t i = 0; i < n; ++i) out.pixels[i * nc + c] = planes[c].second[i];
  return out;
}

}  // namespace hbil::io
