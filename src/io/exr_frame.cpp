// exr_frame.cpp: see exr_frame.h.
#include "io/exr_frame.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfThreading.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>

#include "hbil/error.h"
#include "io/camera_io.h"
#include "io/exr_deflate.h"
#include "io/header_size.h"

namespace hbil::io {

namespace fs = std::filesystem;
using nlohmann::json;

const std::vector<std::string>& field_components(const std::string& field) {
  static const std::vector<std::string> depth = {"Z"}, xyz = {"X", "Y", "Z"}, alpha = {"A"},
                                        rgb = {"R", "G", "B"}, value = {"X"}, motion = {"X", "Y"},
                                        red = {"R"};
  if (field == "depth" || field == "backdepth") return depth;
  if (field == "normal" || field == "position") return xyz;
  if (field == "alpha") return alpha;
  if (field == "metallic") return value;  // a Blender value AOV: <layer>.<name>.X
  if (field == "escape") return red;      // Blender's AO pass: <layer>.AO.R (R = G = B)
  if (field == "vector") return motion;   // Blender's Vector: X, Y towards the previous frame
  return rgb;  // colour passes: diffcol, diffdir, emit, env, gloss*, trans*
}

std::string InputFrame::where() const {
  return "frame " + std::to_string(frame) + " (" + path + ")";
}

namespace {

int channel_index(const OIIO::ImageSpec& spec, const std::string& name) {
  for (int c = 0; c < spec.nchannels; ++c)
    if (spec.channelnames[c] == name) return c;
  return -1;
}

// Candidate channel-name lists for a field, best first.
std::vector<std::vector<std::string>> candidates(const std::string& field, const json& spec_value,
                                                 const std::string& layer) {
  const auto& comps = field_components(field);
  std::vector<std::vector<std::string>> out;
  if (spec_value.is_array()) {
    out.push_back(spec_value.get<std::vector<std::string>>());
    return out;
  }
  const std::string name = spec_value.get<std::string>();
  const bool single_channel = comps.size() == 1 && name.find('.') != std::string::npos;
  for (const std::string& prefix : {layer.empty() ? std::string() : layer + ".", std::string()}) {
    std::vector<std::string> names;
    for (const auto& comp : comps)
      names.push_back(prefix + name + (single_channel ? "" : "." + comp));
    out.push_back(names);
    if (layer.empty()) break;
  }
  return out;
}

std::string join(const std::vector<std::string>& v, const std::string& sep = ", ") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

}  // namespace

namespace {

// The view layer and the channels of every field in f.spec (see InputFrame).
void resolve_channels(InputFrame& f, const Params& p) {
  // View layer: given, or the prefix of the first channel that ends in .<normal pass>.X, else
  // .<depth pass>.Z (Blender's default is "ViewLayer"), never the back-face layer's depth
  // (a "BackFaces" layer has Depth only and sorts first).
  f.view_layer = p.view_layer;
  f.channels.clear();
  f.wanted.clear();
  const json& back = p.passes.count("backdepth") ? p.passes.at("backdepth") : json();
  const std::string back_channel = back.is_string() ? back.get<std::string>() : "";
  if (f.view_layer.empty()) {
    for (const char* field : {"normal", "depth"}) {
      const json& v = p.passes.at(field);
      if (!v.is_string()) continue;
      const std::string tail = "." + v.get<std::string>() + "." + field_components(field)[0];
      for (const auto& ch : f.spec.channelnames)
        if (ch != back_channel && ch.size() > tail.size() &&
            ch.compare(ch.size() - tail.size(), tail.size(), tail) == 0) {
          f.view_layer = ch.substr(0, ch.size() - tail.size());
          break;
        }
      if (!f.view_layer.empty()) break;
    }
  }
  for (const auto& field : gbuffer_fields()) {
    auto it = p.passes.find(field);
    // An empty pass name switches a field off (passes.backdepth="" ignores back faces).
    if (it == p.passes.end() || (it->second.is_string() && it->second.get<std::string>().empty()))
      continue;
    const auto cands = candidates(field, it->second, f.view_layer);
    f.wanted[field] = cands.front();
    for (const auto& names : cands) {
      std::vector<int> idx;
      for (const auto& n : names) idx.push_back(channel_index(f.spec, n));
      if (std::find(idx.begin(), idx.end(), -1) == idx.end()) {
        f.channels[field] = idx;
        f.wanted[field] = names;
        break;
      }
    }
  }
}

}  // namespace

InputFrame open_frame(const std::string& path, int frame, const Params& p) {
  InputFrame f;
  f.path = path;
  f.frame = frame;
  if (!fs::exists(path)) throw Error(Exit::input, f.where() + ": file not found");
  auto in = open_image_input(path, f.where());
  if (!in) throw Error(Exit::input, f.where() + ": cannot read: " + OIIO::geterror());
  f.openexr = std::string(in->format_name()) == "openexr";
  // A multi-part file: the part that holds the most G-buffer fields (the first of equals),
  // so that a beauty part written before the passes is passed over.
  size_t best = 0;
  for (int part = 0; in->seek_subimage(part, 0); ++part) {
    InputFrame candidate = f;
    candidate.part = part;
    candidate.spec = in->spec();
    resolve_channels(candidate, p);
    if (part == 0 || candidate.channels.size() > best) {
      best = candidate.channels.size();
      f = std::move(candidate);
    }
  }
  in->close();
  if (f.spec.deep) throw Error(Exit::input, f.where() + ": deep images are not supported");
  check_header_size(path, f.spec, f.openexr, f.where());  // before anything is sized from it
  return f;
}

Params resolve_outputs(const InputFrame& f, const Params& p, std::string* why_dropped) {
  if (why_dropped) why_dropped->clear();
  return hbil::resolve_outputs(p, [&](const std::string& o) {
    // ao and bentcone are always kept: what they lack is an error fields_needed() reports.
    if (o == "ao" || o == "bentcone") return true;
    Params one = p;
    one.outputs = {o};
    try {
      fields_needed(f, one);
      return true;
    } catch (const Error& e) {
      if (why_dropped && why_dropped->empty()) *why_dropped = e.what();
      return false;
    }
  });
}

void require_fields(const InputFrame& f, const std::vector<std::string>& fields,
                    const std::string& needed_by) {
  for (const std::string& field : fields)
    if (!f.has(field))
      throw Error(Exit::missing_pass, f.where() + ": missing pass: " + field +
                                          " (looked for channels " + join(f.wanted.at(field)) +
                                          "; needed by " + needed_by + "; map it with passes." +
                                          field + ")");
}

std::vector<std::string> fields_needed(const InputFrame& f, const Params& requested) {
  const Params p = requested.wants("auto") ? resolve_outputs(f, requested) : requested;
  std::vector<std::string> need;
  const bool geometry = !p.outputs.empty();  // every output comes from the horizon search
  if (geometry) {
    if (!f.has("normal"))
      throw Error(Exit::missing_pass, f.where() + ": missing pass: normal (looked for channels " +
                                          join(f.wanted.at("normal")) +
                                          "; map it with passes.normal)");
    if (f.has("depth")) need.push_back("depth");
    if (f.has("position") && (!f.has("depth") || camera_from_position(f)))
      need.push_back("position");  // the geometry, or the camera solved from it (find_camera)
    if (!f.has("depth") && !f.has("position"))
      throw Error(Exit::missing_pass, f.where() + ": missing pass: depth or position (looked for " +
                                          join(f.wanted.at("depth")) + " and " +
                                          join(f.wanted.at("position")) +
                                          "; map them with passes.depth / passes.position)");
    need.push_back("normal");
    // Per-pixel occluder thickness for the visibility bitmask (read only where it is used).
    if (p.method == "bitmask" && f.has("backdepth")) need.push_back("backdepth");
  }
  const bool needs_albedo = p.ao_multibounce && p.wants("ao");
  if (needs_albedo && !(p.wants("irradiance") || p.wants("indirect") || p.wants("composite"))) {
    if (!f.has("diffcol"))
      throw Error(Exit::missing_pass, f.where() + ": missing pass: diffcol (looked for channels " +
                                          join(f.wanted.at("diffcol")) +
                                          "; needed by ao_multibounce)");
    need.push_back("diffcol");
  }
  if (p.wants("irradiance") || p.wants("indirect") || p.wants("composite")) {
    // Source radiance DiffCol × DiffDir (+ Emit where the emitters' light is not in DiffDir;
    // HBIL eq. 16-17); Emit is optional, and the composite and unseen_radiance "auto" read it.
    require_fields(f, {"diffcol", "diffdir"}, "irradiance, indirect and composite");
    need.insert(need.end(), {"diffcol", "diffdir"});
    if (f.has("emit")) need.push_back("emit");
    // What escapes the whole scene, for the fill of unseen_radiance "auto" (unseen.h).
    if (p.unseen_radiance_auto && f.has("escape")) need.push_back("escape");
  }
  // HBIL eq. 19: the receiver's (1 − F0) on the light it reflects diffusely, from F0 or else
  // from metallic, when a preset maps one.
  if (p.wants("irradiance") || p.wants("indirect") || p.wants("composite") || p.wants("farfield")) {
    if (f.has("f0"))
      need.push_back("f0");
    else if (f.has("metallic"))
      need.push_back("metallic");
  }
  if (p.wants("composite"))  // passed through when present
    for (const char* field :
         {"env", "glosscol", "glossdir", "glossind", "transcol", "transdir", "transind"})
      if (f.has(field)) need.push_back(field);
  // Motion vectors for the temporal chain's gather reprojection.
  if (geometry && p.temporal && p.reprojection != "scatter") {
    if (f.has("vector"))
      need.push_back("vector");
    else if (p.reprojection == "vector")
      throw Error(Exit::missing_pass, f.where() + ": missing pass: vector (looked for channels " +
                                          join(f.wanted.at("vector")) +
                                          "; needed by reprojection \"vector\")");
  }
  if (f.has("alpha")) need.push_back("alpha");
  return need;
}

namespace {

// Where the channels of one field go: channel c of pixel i at dst[i * idx.size() + c].
struct FieldTarget {
  std::vector<int> idx;  // the field's channels in the file
  float* dst;
  std::uint16_t* half = nullptr;  // instead of dst: HALF channels kept as their bits
};

// Reads the channels of several fields in one pass: EXR compresses all channels of a block
// of scanlines together, so every separate read would decompress the whole file again.
// OpenEXR files go through OpenEXR, which decompresses each block once and converts only the
// channels asked for, straight into their fields (in parallel over blocks); ZIP, ZIPS and
// uncompressed scanline files, the renderers' usual output, through exr_deflate's faster
// inflate. Other formats go through OpenImageIO in blocks of 64 rows over the smallest
// channel range holding all fields.
void read_exr_channels(const InputFrame& f, const std::vector<FieldTarget>& fields) {
  if (fields.empty()) return;
  try {
    // Part 0 (every single-part file) through InputFile, which the deflate path takes;
    // another part of a multi-part file through InputPart.
    std::optional<Imf::InputFile> single;
    std::optional<Imf::MultiPartInputFile> multi;
    std::optional<Imf::InputPart> part;
    if (f.part == 0) {
      single.emplace(f.path.c_str(), Imf::globalThreadCount());
    } else {
      multi.emplace(f.path.c_str(), Imf::globalThreadCount());
      part.emplace(*multi, f.part);
    }
    const Imf::Header& header = single ? single->header() : part->header();
    const Imath::Box2i dw = header.dataWindow();
    const size_t w = size_t(dw.max.x - dw.min.x + 1), h = size_t(dw.max.y - dw.min.y + 1);
    if (int(w) != f.spec.width || int(h) != f.spec.height)
      throw Error(Exit::input, f.where() + ": the data window changed since the header was read");
    std::vector<ExrChannelTarget> targets;
    for (const FieldTarget& t : fields)
      for (size_t c = 0; c < t.idx.size(); ++c)
        targets.push_back({f.spec.channelnames[t.idx[c]], t.half ? nullptr : t.dst + c,
                           t.idx.size(), t.half ? t.half + c : nullptr});
    if (single && read_deflate_scanlines(*single, targets)) return;
    Imf::FrameBuffer fb;
    for (const FieldTarget& t : fields) {
      const size_t m = t.idx.size();
      for (size_t c = 0; c < m; ++c)
        fb.insert(f.spec.channelnames[t.idx[c]],
                  t.half ? Imf::Slice::Make(Imf::HALF, t.half + c, dw, sizeof(std::uint16_t) * m,
                                            sizeof(std::uint16_t) * m * w)
                         : Imf::Slice::Make(Imf::FLOAT, t.dst + c, dw, sizeof(float) * m,
                                            sizeof(float) * m * w));
    }
    if (single) {
      single->setFrameBuffer(fb);
      single->readPixels(dw.min.y, dw.max.y);
    } else {
      part->setFrameBuffer(fb);
      part->readPixels(dw.min.y, dw.max.y);
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(Exit::input, f.where() + ": cannot read its pixels: " + e.what());
  }
}

void read_channels(const InputFrame& f, const std::vector<FieldTarget>& fields) {
  if (fields.empty()) return;
  auto in = open_image_input(f.path, f.where());
  if (!in) throw Error(Exit::input, f.where() + ": cannot read: " + OIIO::geterror());
  const int w = f.spec.width, h = f.spec.height;
  int lo = f.spec.nchannels, hi = 0;
  for (const FieldTarget& t : fields)
    for (int c : t.idx) lo = std::min(lo, c), hi = std::max(hi, c + 1);
  const int n = hi - lo, rows = 64;
  std::vector<float> block(size_t(w) * rows * n);
  for (int y0 = 0; y0 < h; y0 += rows) {
    const int y1 = std::min(h, y0 + rows);
    if (!in->read_scanlines(f.part, 0, f.spec.y + y0, f.spec.y + y1, 0, lo, hi,
                            OIIO::TypeDesc::FLOAT, block.data()))
      throw Error(Exit::input, f.where() + ": cannot read rows " + std::to_string(y0) + "-" +
                                   std::to_string(y1 - 1) + ": " + in->geterror());
    for (const FieldTarget& t : fields) {
      const size_t m = t.idx.size();
      for (size_t i = 0; i < size_t(w) * (y1 - y0); ++i)
        for (size_t c = 0; c < m; ++c)
          t.dst[(size_t(y0) * w + i) * m + c] = block[i * n + (t.idx[c] - lo)];
    }
  }
}

// The largest magnitudes read_fields takes (see exr_frame.h).
constexpr float kMaxColour = 1e9f, kMaxAlbedo = 1e3f, kMaxMotion = 1e6f;

// Whether every one of v's n values lies in [lo, hi] (a NaN does not): one pass without a
// branch a value, which the compiler vectorises, before the loops that say which value is
// wrong and how.
bool all_within(const float* v, size_t n, float lo, float hi) {
  unsigned ok = 1;
  for (size_t i = 0; i < n; ++i) ok &= unsigned(v[i] >= lo) & unsigned(v[i] <= hi);
  return ok != 0;
}

[[noreturn]] void bad_value(const InputFrame& f, int channel, size_t i, float v,
                            const std::string& what) {
  std::ostringstream s;
  s << f.where() << ": layer " << f.spec.channelnames[channel] << ": " << what << " at pixel ("
    << i % f.spec.width << ", " << i / f.spec.width << "): " << v;
  throw Error(Exit::bad_data, s.str());
}

}  // namespace

bool emission_gathered(const InputFrame& f, const Params& p) {
  if (p.emission != "auto") return p.emission == "gathered";
  // hbil import-povray's frames: POV-Ray's emitters light other surfaces only through
  // radiosity, which the import puts in DiffInd, not DiffDir.
  return f.spec.get_string_attribute("hbil:source").find("(hbil import-povray)") !=
         std::string::npos;
}

bool windowed(const OIIO::ImageSpec& spec) {
  return spec.full_width != spec.width || spec.full_height != spec.height ||
         spec.full_x != spec.x || spec.full_y != spec.y;
}

GBuffer read_fields(const InputFrame& f, const std::vector<std::string>& fields, const Params& p,
                    bool keep_half) {
  GBuffer g;
  g.width = f.spec.width;
  g.height = f.spec.height;
  if (windowed(f.spec)) {
    g.display_x = f.spec.full_x - f.spec.x;
    g.display_y = f.spec.full_y - f.spec.y;
    g.display_width = f.spec.full_width;
    g.display_height = f.spec.full_height;
  }
  g.emit_gathered = emission_gathered(f, p);
  const size_t n = g.pixels();
  // Every field is read straight into its own array of the G-buffer, then checked in place.
  auto scalar = [&](const std::string& field) -> std::vector<float>& {
    if (field == "depth") return g.depth;
    if (field == "backdepth") return g.backdepth;
    if (field == "alpha") return g.alpha;
    if (field == "vector") return g.motion;
    if (field == "escape") return g.escape;
    return g.metallic;
  };
  std::vector<FieldTarget> targets;
  for (const auto& field : fields) {
    const std::vector<int>& idx = f.channels.at(field);
    float* dst = nullptr;
    bool half = keep_half && f.openexr && GBuffer::packable(field) && idx.size() == 3;
    for (int c : idx) half = half && f.spec.channelformat(c) == OIIO::TypeDesc::HALF;
    if (half) {
      g.packed.emplace_back(field, std::vector<std::uint16_t>(n * 3));
      targets.push_back({idx, nullptr, g.packed.back().second.data()});
      continue;
    }
    if (std::vector<Vec3>* rgb = g.rgb(field)) {
      rgb->resize(n);
      dst = &rgb->data()->x;
    } else {
      std::vector<float>& v = scalar(field);
      v.resize(n * idx.size());
      dst = v.data();
    }
    targets.push_back({idx, dst});
  }
  if (f.openexr)
    read_exr_channels(f, targets);
  else
    read_channels(f, targets);
  for (size_t k = 0; k < fields.size(); ++k) {
    const std::string& field = fields[k];
    const std::vector<int>& idx = targets[k].idx;
    const float* v = targets[k].dst;
    const size_t m = idx.size(), count = n * m;
    if (const std::uint16_t* bits = targets[k].half) {
      unsigned special = 0;  // exponent all ones somewhere, found without a branch a value
      for (size_t i = 0; i < count; ++i) special |= unsigned((bits[i] & 0x7c00u) == 0x7c00u);
      for (size_t i = 0; special && i < count; ++i)
        if ((bits[i] & 0x7c00u) == 0x7c00u)  // exponent all ones: infinity or NaN
          bad_value(f, idx[i % m], i / m, half_to_float(bits[i]), "non-finite " + field);
    } else if (field == "depth" || field == "backdepth") {
      if (all_within(v, count, 0.f, std::numeric_limits<float>::max())) continue;
      for (size_t i = 0; i < count; ++i) {
        if (!std::isfinite(v[i])) bad_value(f, idx[0], i, v[i], "non-finite " + field);
        if (v[i] < 0) bad_value(f, idx[0], i, v[i], "negative " + field);
      }
    } else if (field == "alpha") {
      // Any finite value is taken (only alpha > 0 matters, gbuffer.h); it becomes the
      // composite's alpha, so a NaN or an infinity would reach the output.
      if (all_within(v, count, -kMaxColour, kMaxColour)) continue;
      for (size_t i = 0; i < count; ++i) {
        if (!std::isfinite(v[i])) bad_value(f, idx[0], i, v[i], "non-finite alpha");
        if (std::abs(v[i]) > kMaxColour) bad_value(f, idx[0], i, v[i], "alpha beyond +-1e9");
      }
    } else if (field == "vector") {
      // Blender: the previous-frame position of pixel (col, row), rows top-down, is
      // (col + X, row − Y) (samples/README.md); stored as the raster offset (X, −Y).
      if (!all_within(v, count, -kMaxMotion, kMaxMotion))
        for (size_t i = 0; i < count; ++i) {
          if (!std::isfinite(v[i])) bad_value(f, idx[i % 2], i / 2, v[i], "non-finite vector");
          if (std::abs(v[i]) > kMaxMotion)
            bad_value(f, idx[i % 2], i / 2, v[i], "vector beyond +-1e6 pixels");
        }
      for (size_t i = 1; i < count; i += 2) g.motion[i] = -g.motion[i];
    } else {
      // Normal, position and colour passes. The bounds keep every product of them (an albedo times
      // light, for each bounce) finite in float; no render comes near them.
      const bool albedo = field.size() > 3 && field.compare(field.size() - 3, 3, "col") == 0;
      const float bound = albedo ? kMaxAlbedo : kMaxColour;
      if (all_within(v, count, -bound, bound)) continue;
      const std::string what = "non-finite " + field;
      const std::string beyond = field + (albedo ? " beyond +-1000 (an albedo)" : " beyond +-1e9");
      for (size_t i = 0; i < count; ++i) {
        if (!std::isfinite(v[i])) bad_value(f, idx[i % m], i / m, v[i], what);
        if (std::abs(v[i]) > bound) bad_value(f, idx[i % m], i / m, v[i], beyond);
      }
    }
  }
  return g;
}

bool camera_from_position(const InputFrame& f) {
  return f.has("position") && !fs::exists(sidecar_path_for(f.path)) &&
         !camera_from_exr_attributes(f.spec);
}

Camera find_camera(const InputFrame& f, GBuffer& g, const Params& p, double max_rms_px) {
  Camera cam;
  const std::string sidecar = sidecar_path_for(f.path);
  if (fs::exists(sidecar)) {
    cam = camera_from_sidecar(sidecar);
    // A sidecar describes the frame as framed: the display window. The pixels are the data
    // window's (a crop, or an overscan's guard band), whose raster starts full - data
    // origin further on.
    if (windowed(f.spec)) {
      if (cam.width != f.spec.full_width || cam.height != f.spec.full_height) {
        std::ostringstream s;
        s << f.where() << ": camera " << cam.source << " is for " << cam.width << "x" << cam.height
          << " but the image's display window is " << f.spec.full_width << "x" << f.spec.full_height
          << " (its data window " << f.spec.width << "x" << f.spec.height << " at (" << f.spec.x
          << ", " << f.spec.y << "))";
        throw Error(Exit::camera, s.str());
      }
      cam.cx += double(f.spec.full_x - f.spec.x);
      cam.cy += double(f.spec.full_y - f.spec.y);
      cam.width = f.spec.width;
      cam.height = f.spec.height;
    }
  } else if (auto attr = camera_from_exr_attributes(f.spec)) {
    cam = *attr;
  } else if (f.has("position")) {
    if (g.position.empty()) g.position = read_fields(f, {"position"}, p).position;
    try {
      cam = solve_camera_from_positions(g.width, g.height, g.position);
    } catch (const Error& e) {
      throw Error(e.code(), f.where() + ": " + e.what());
    }
    if (cam.reprojection_rms_px > max_rms_px) {
      std::ostringstream s;
      s << f.where() << ": the camera solved from " << join(f.wanted.at("position"))
        << " reprojects with an RMS error of " << cam.reprojection_rms_px
        << " px (allowed: " << max_rms_px << " px); provide a camera sidecar " << sidecar
        << " (samples/blender/export_camera.py writes it)";
      throw Error(Exit::camera, s.str());
    }
  } else {
    throw Error(Exit::camera,
                f.where() + ": no camera: none of a sidecar " + sidecar +
                    " (samples/blender/export_camera.py writes it), the EXR attributes "
                    "worldToCamera and worldToNDC (" +
                    camera_attribute_status(f.spec) + "), or a Position pass (looked for " +
                    join(f.wanted.at("position")) + ") to solve it from");
  }
  if (cam.width != f.spec.width || cam.height != f.spec.height) {
    std::ostringstream s;
    s << f.where() << ": camera " << cam.source << " is for " << cam.width << "x" << cam.height
      << " but the image is " << f.spec.width << "x" << f.spec.height;
    throw Error(Exit::camera, s.str());
  }
  return cam;
}

}  // namespace hbil::io
