// exr_output.cpp: see exr_output.h.
#include "io/exr_output.h"

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hbil/error.h"
#include "io/camera_io.h"
#include "io/exr_rle.h"
#include "io/half_rows.h"

namespace hbil::io {

namespace fs = std::filesystem;

std::vector<OutputChannel> output_plan(const AoFrame& f, const Params& p) {
  std::vector<OutputChannel> plan;
  // Colour layers as half where the preset says so; data layers (ao, bentcone, history)
  // always 32-bit.
  auto add = [&](const std::string& name, const float* src, size_t stride, bool colour) {
    plan.push_back({name, src, stride, colour && p.colour_half});
  };
  auto rgb = [&](const std::string& layer, const std::vector<Vec3>& v, bool colour = true) {
    for (int k = 0; k < 3; ++k) add(layer + "." + "RGB"[k], &v.data()->x + k, 3, colour);
  };
  for (const auto& o : p.outputs) {
    if (o == "ao" && f.ao_rgb.empty()) add("ao.Y", f.ao.data(), 1, false);
    if (o == "ao" && !f.ao_rgb.empty()) rgb("ao", f.ao_rgb, false);
    if (o == "farfield") rgb("farfield", f.farfield);
    if (o == "composite") {
      rgb("composite", f.composite);
      add("composite.A", f.composite_alpha.empty() ? nullptr : f.composite_alpha.data(), 1, true);
    }
    if (o == "bentcone") {
      for (int k = 0; k < 3; ++k)
        add(std::string("bentcone.") + "XYZ"[k], &f.bent.data()->x + k, 3, false);
      add("bentcone.W", f.cone_cos.data(), 1, false);
    }
    if (o == "irradiance") rgb("irradiance", f.irradiance);
    if (o == "indirect") rgb("indirect", f.indirect);
    // Without a temporal chain every pixel has one frame of history.
    if (o == "history") add("history.Y", f.history.empty() ? nullptr : f.history.data(), 1, false);
  }
  return plan;
}

size_t pixel_bytes(const std::vector<OutputChannel>& plan) {
  size_t n = 0;
  for (const OutputChannel& c : plan) n += c.half ? 2 : 4;
  return n;
}

namespace {

// output_rows one value at a time, where a row holds a non-finite value.
std::optional<NonFinite> output_rows_checked(const std::vector<OutputChannel>& plan, int width,
                                             int y0, int y1, unsigned char* dst) {
  const size_t stride = pixel_bytes(plan), first = size_t(y0) * width, n = size_t(y1 - y0) * width;
  constexpr float kHalfMax = 65504.f;  // HALF_MAX: the largest finite half
  std::optional<NonFinite> bad;
  size_t offset = 0;
  for (size_t ch = 0; ch < plan.size(); ++ch) {
    const OutputChannel& c = plan[ch];
    unsigned char* out = dst + offset;
    for (size_t i = 0; i < n; ++i, out += stride) {
      float v = c.src ? c.src[(first + i) * c.stride] : 1.f;
      if (!std::isfinite(v) && (!bad || first + i < bad->pixel)) bad = NonFinite{first + i, ch, v};
      if (c.half) {
        if (std::isfinite(v)) v = std::clamp(v, -kHalfMax, kHalfMax);
        const Imath::half h(v);
        std::memcpy(out, &h, 2);
      } else {
        std::memcpy(out, &v, 4);
      }
    }
    offset += c.half ? 2 : 4;
  }
  return bad;
}

}  // namespace

std::optional<NonFinite> output_rows(const std::vector<OutputChannel>& plan, int width, int y0,
                                     int y1, unsigned char* dst) {
  // Each channel converted as a whole (half_rows.h), then packed; where a value is not
  // finite, the rows again one value at a time, which finds the first.
  const size_t stride = pixel_bytes(plan), first = size_t(y0) * width, n = size_t(y1 - y0) * width;
  thread_local std::vector<std::uint16_t> halves;
  size_t offset = 0;
  bool finite = true;
  for (const OutputChannel& c : plan) {
    unsigned char* out = dst + offset;
    if (c.half) {
      halves.resize(n);
      if (c.src)
        finite &= floats_to_half_bits(c.src + first * c.stride, c.stride, n, halves.data());
      else
        std::fill(halves.begin(), halves.end(), Imath::half(1.f).bits());
      for (size_t i = 0; i < n; ++i, out += stride) std::memcpy(out, &halves[i], 2);
    } else {
      std::uint32_t special = 0;  // exponent bits all set: an infinity or a NaN
      for (size_t i = 0; i < n; ++i, out += stride) {
        const float v = c.src ? c.src[(first + i) * c.stride] : 1.f;
        std::uint32_t bits;
        std::memcpy(&bits, &v, 4);
        special |= std::uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        std::memcpy(out, &v, 4);
      }
      finite &= special == 0;
    }
    offset += c.half ? 2 : 4;
  }
  if (finite) return std::nullopt;
  return output_rows_checked(plan, width, y0, y1, dst);
}

std::string camera_json(const Camera& c) {
  nlohmann::json j;
  j["source"] = c.source;
  j["resolution"] = {c.width, c.height};
  j["fx"] = c.fx;
  j["fy"] = c.fy;
  j["cx"] = c.cx;
  j["cy"] = c.cy;
  j["world_to_view_R"] = {{c.R.m[0][0], c.R.m[0][1], c.R.m[0][2]},
                          {c.R.m[1][0], c.R.m[1][1], c.R.m[1][2]},
                          {c.R.m[2][0], c.R.m[2][1], c.R.m[2][2]}};
  j["world_to_view_t"] = {c.t.x, c.t.y, c.t.z};
  j["view_convention"] = "x right, y down, z forward; raster (col+0.5, row+0.5)";
  if (c.reprojection_rms_px > 0) j["reprojection_rms_px"] = c.reprojection_rms_px;
  return j.dump();
}

std::string write_temporary(const std::string& final_path, const AoFrame& f,
                            const OIIO::ImageSpec& input_header, const Params& p, const Camera& cam,
                            std::optional<int> frame, const std::string& job) {
  Temporary tmp(final_path);
  const std::vector<OutputChannel> plan = output_plan(f, p);
  OIIO::ImageSpec spec(f.width, f.height, int(plan.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames.clear();
  bool any_half = false;
  for (const OutputChannel& c : plan) {
    spec.channelnames.push_back(c.name);
    spec.channelformats.push_back(c.half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
    any_half |= c.half;
  }
  if (!any_half) spec.channelformats.clear();
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  // The input's data and display windows (a crop, or an overscan's guard band), which the
  // frame's pixels cover as its input's do.
  if (input_header.width == f.width && input_header.height == f.height) {
    spec.x = input_header.x;
    spec.y = input_header.y;
    spec.full_x = input_header.full_x;
    spec.full_y = input_header.full_y;
    spec.full_width = input_header.full_width;
    spec.full_height = input_header.full_height;
  }
  // The input's metadata first (stamp, cycles.*, ...), minus what describes its storage and
  // its writer: BlenderMultiChannel tells Blender the channels are its own render layers,
  // which hbil's are not; Software is hbil.
  for (const OIIO::ParamValue& a : input_header.extra_attribs) {
    const std::string name = a.name().string();
    if (name.rfind("oiio:", 0) == 0 || name.rfind("openexr:", 0) == 0 || name == "compression" ||
        name == "channelformats" || name == "worldtocamera" || name == "worldtoNDC" ||
        name == "worldToCamera" || name == "worldToNDC" || name.rfind("hbil:", 0) == 0 ||
        name == "BlenderMultiChannel" || name == "Software")
      continue;
    spec.attribute(name, a.type(), a.data());
  }
  spec.attribute("Software", "hbil " HBIL_VERSION);
  // RLE is compressed by hbil (io/exr_rle.h): OpenEXR writes the frame uncompressed into it.
  const bool own_rle = p.compression == "rle";
  spec.attribute("compression", own_rle ? std::string("none") : p.compression);
  spec.attribute("hbil:version", HBIL_VERSION);
  spec.attribute("hbil:preset", to_json(p).dump());
  spec.attribute("hbil:camera", camera_json(cam));
  if (!job.empty()) spec.attribute("hbil:job", job);
  set_camera_attributes(spec, cam);

  // Declared before the writer, so that a writer destroyed on an error never writes to a
  // proxy already gone.
  std::optional<RleExrWriter> rle;
  auto out = OIIO::ImageOutput::create(tmp.path());
  if (!out)
    throw Error(Exit::output, final_path + ": cannot create an EXR writer: " + OIIO::geterror());
  if (own_rle) {
    rle.emplace(tmp.path());
    if (!out->set_ioproxy(&*rle))
      throw Error(Exit::output, final_path + ": cannot create an EXR writer: " + out->geterror());
  }
  // Written in strips of rows, so that no second copy of the whole frame is made.
  constexpr int kStrip = 64;
  // Each strip is packed in the file's own channel formats (native data: no conversion in
  // OpenImageIO).
  const size_t row_bytes = size_t(f.width) * pixel_bytes(plan);
  std::vector<unsigned char> strip(size_t(kStrip) * row_bytes);
  bool ok = out->open(tmp.path(), spec);
  std::vector<std::optional<NonFinite>> bad(kStrip);  // per row of the strip
  for (int y0 = 0; ok && y0 < f.height; y0 += kStrip) {
    const int y1 = std::min(y0 + kStrip, f.height);
    tbb::parallel_for(y0, y1, [&](int y) {
      bad[y - y0] = output_rows(plan, f.width, y, y + 1, strip.data() + size_t(y - y0) * row_bytes);
    });
    for (int y = y0; y < y1; ++y)
      if (const std::optional<NonFinite>& b = bad[y - y0]) {
        out->close();
        std::ostringstream m;
        if (frame)
          m << "frame " << *frame << " (" << final_path << ")";
        else
          m << final_path;
        m << ": layer " << plan[b->channel].name << ": non-finite value " << b->value
          << " at pixel (" << b->pixel % size_t(f.width) << ", " << b->pixel / size_t(f.width)
          << "); nothing was written (a defect in hbil: please report it with this frame)";
        throw Error(Exit::failure, m.str());
      }
    ok = out->write_scanlines(spec.y + y0, spec.y + y1, 0, OIIO::TypeUnknown, strip.data());
  }
  if (!ok || !out->close()) {
    const std::string why = rle && !rle->why().empty() ? rle->why() : out->geterror();
    throw Error(Exit::output, final_path + ": cannot write: " + why);
  }
  out.reset();
  if (rle) {
    rle->close();
    if (!rle->complete()) throw Error(Exit::output, final_path + ": cannot write: " + rle->why());
  }
  return tmp.keep();
}

void OutputBatch::expect(const std::string& final_path) {
  fs::path dir = fs::absolute(fs::path(final_path)).parent_path(), top;
  for (; !dir.empty() && !fs::exists(dir) && dir != dir.parent_path(); dir = dir.parent_path())
    top = dir;
  if (!top.empty()) created_.insert(top);
}

void OutputBatch::add(const std::string& temporary, const std::string& final_path) {
  files_.emplace_back(temporary, final_path);
}

void OutputBatch::commit() {
  while (!files_.empty()) {
    const auto [temporary, final_path] = files_.front();
    files_.erase(files_.begin());
    io::commit(temporary, final_path);
    committed_ = true;
  }
}

void OutputBatch::discard() noexcept {
  for (const auto& f : files_) discard_temporary(f.first);
  files_.clear();
  std::error_code ec;
  // The folders the command created go too, unless they hold files it finished.
  if (!committed_)
    for (const auto& dir : created_) fs::remove_all(dir, ec);
}

void write_file(const std::string& path, const std::string& text) {
  Temporary tmp(path);
  {
    std::ofstream out(tmp.path(), std::ios::binary);
    out << text;
    if (!out.flush()) throw Error(Exit::output, path + ": cannot write");
  }
  commit(tmp.keep(), path);
}

void commit(const std::string& temporary, const std::string& final_path) {
  std::error_code ec;
  fs::rename(temporary, final_path, ec);
  release_temporary(temporary);
  if (ec) {
    discard_temporary(temporary);
    throw Error(Exit::output,
                final_path + ": cannot rename the finished frame into place: " + ec.message());
  }
}

}  // namespace hbil::io
