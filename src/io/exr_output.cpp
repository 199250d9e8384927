// exr_output.cpp: see exr_output.h.
#include "io/exr_output.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "hbil/error.h"
#include "io/camera_io.h"

namespace hbil::io {

namespace fs = std::filesystem;

std::vector<std::string> output_channels(const AoFrame& f, const Params& p) {
  std::vector<std::string> ch;
  for (const auto& o : p.outputs) {
    if (o == "ao" && f.ao_rgb.empty()) ch.push_back("ao.Y");
    if (o == "ao" && !f.ao_rgb.empty()) ch.insert(ch.end(), {"ao.R", "ao.G", "ao.B"});
    if (o == "farfield") ch.insert(ch.end(), {"farfield.R", "farfield.G", "farfield.B"});
    if (o == "composite")
      ch.insert(ch.end(), {"composite.R", "composite.G", "composite.B", "composite.A"});
    if (o == "bentcone")
      ch.insert(ch.end(), {"bentcone.X", "bentcone.Y", "bentcone.Z", "bentcone.W"});
    if (o == "irradiance") ch.insert(ch.end(), {"irradiance.R", "irradiance.G", "irradiance.B"});
    if (o == "indirect") ch.insert(ch.end(), {"indirect.R", "indirect.G", "indirect.B"});
    if (o == "history") ch.push_back("history.Y");
  }
  return ch;
}

void output_rows(const AoFrame& f, const Params& p, int y0, int y1, float* px) {
  for (size_t i = size_t(y0) * f.width; i < size_t(y1) * f.width; ++i)
    for (const auto& o : p.outputs) {
      if (o == "ao" && f.ao_rgb.empty()) *px++ = f.ao[i];
      if (o == "history") *px++ = f.history.empty() ? 1.f : f.history[i];
      if (o == "ao" && !f.ao_rgb.empty())
        *px++ = f.ao_rgb[i].x, *px++ = f.ao_rgb[i].y, *px++ = f.ao_rgb[i].z;
      if (o == "composite")
        for (int k = 0; k < 4; ++k) *px++ = f.composite[4 * i + k];
      if (o == "bentcone") {
        *px++ = f.bent[i].x;
        *px++ = f.bent[i].y;
        *px++ = f.bent[i].z;
        *px++ = f.cone_cos[i];
      }
      for (const auto* rgb :
           {o == "irradiance" ? &f.irradiance : nullptr, o == "indirect" ? &f.indirect : nullptr,
            o == "farfield" ? &f.farfield : nullptr})
        if (rgb) {
          *px++ = (*rgb)[i].x;
          *px++ = (*rgb)[i].y;
          *px++ = (*rgb)[i].z;
        }
    }
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

std::string prepare_temporary(const std::string& final_path, const std::string& tag) {
  const fs::path final_p(final_path);
  std::error_code ec;
  if (final_p.has_parent_path()) {
    fs::create_directories(final_p.parent_path(), ec);
    if (ec)
      throw Error(Exit::output, final_path + ": cannot create folder " +
                                    final_p.parent_path().string() + ": " + ec.message());
  }
  static std::atomic<int> counter{0};
  // Appended piece by piece: "." + std::string trips GCC 12's -Wrestrict (a false positive).
  std::string name = ".";
  name += final_p.stem().string();
  name += ".hbil-tmp-" + tag + std::to_string(getpid()) + "-" + std::to_string(counter++);
  name += final_p.extension().string();
  return (final_p.parent_path() / name).string();
}

std::string write_temporary(const std::string& final_path, const AoFrame& f,
                            const OIIO::ImageSpec& input_header, const Params& p,
                            const Camera& cam) {
  const fs::path tmp = prepare_temporary(final_path);
  std::error_code ec;
  const std::vector<std::string> channels = output_channels(f, p);
  OIIO::ImageSpec spec(f.width, f.height, int(channels.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames = channels;
  // Colour layers as half where the preset says so; data layers (ao, bentcone, history)
  // always 32-bit.
  if (p.colour_half) {
    bool any_half = false;
    for (const std::string& ch : channels) {
      const std::string layer = ch.substr(0, ch.find('.'));
      const bool colour = layer == "irradiance" || layer == "indirect" || layer == "farfield" ||
                          layer == "composite";
      spec.channelformats.push_back(colour ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
      any_half |= colour;
    }
    if (!any_half) spec.channelformats.clear();
  }
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  // The input's metadata first (stamp, cycles.*, ...), minus what describes its storage.
  for (const OIIO::ParamValue& a : input_header.extra_attribs) {
    const std::string name = a.name().string();
    if (name.rfind("oiio:", 0) == 0 || name.rfind("openexr:", 0) == 0 || name == "compression" ||
        name == "channelformats" || name == "worldtocamera" || name == "worldtoNDC" ||
        name == "worldToCamera" || name == "worldToNDC" || name.rfind("hbil:", 0) == 0)
      continue;
    spec.attribute(name, a.type(), a.data());
  }
  spec.attribute("compression", p.compression);
  spec.attribute("hbil:version", HBIL_VERSION);
  spec.attribute("hbil:preset", to_json(p).dump());
  spec.attribute("hbil:camera", camera_json(cam));
  set_camera_attributes(spec, cam);

  auto out = OIIO::ImageOutput::create(tmp.string());
  if (!out)
    throw Error(Exit::output, final_path + ": cannot create an EXR writer: " + OIIO::geterror());
  // Written in strips of rows, so that no second copy of the whole frame is made.
  constexpr int kStrip = 64;
  std::vector<float> strip(size_t(kStrip) * f.width * channels.size());
  bool ok = out->open(tmp.string(), spec);
  for (int y0 = 0; ok && y0 < f.height; y0 += kStrip) {
    const int y1 = std::min(y0 + kStrip, f.height);
    output_rows(f, p, y0, y1, strip.data());
    ok = out->write_scanlines(y0, y1, 0, OIIO::TypeDesc::FLOAT, strip.data());
  }
  if (!ok || !out->close()) {
    const std::string why = out->geterror();
    fs::remove(tmp, ec);
    throw Error(Exit::output, final_path + ": cannot write: " + why);
  }
  return tmp.string();
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
  for (const auto& [temporary, final_path] : files_) io::commit(temporary, final_path);
  files_.clear();
}

void OutputBatch::discard() noexcept {
  std::error_code ec;
  for (const auto& f : files_) fs::remove(f.first, ec);
  for (const auto& dir : created_) fs::remove_all(dir, ec);
  files_.clear();
}

void commit(const std::string& temporary, const std::string& final_path) {
  std::error_code ec;
  fs::rename(temporary, final_path, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw Error(Exit::output,
                final_path + ": cannot rename the finished frame into place: " + ec.message());
  }
}

}  // namespace hbil::io
