// info.cpp: `hbil info FILE`: what a frame holds and what hbil can compute from it.
#include <algorithm>
#include <iostream>
#include <map>

#include "cli/commands.h"
#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "hbil/reduced.h"
#include "hbil/scene_scale.h"
#include "hbil/unseen.h"
#include "io/camera_io.h"
#include "io/exr_frame.h"
#include "io/sequence.h"
#include "pipeline/calibration.h"

namespace hbil::cli {

namespace {

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

void info(const std::string& path, const ParamOptions& po) {
  Params p = po.load();
  // The calibration a run of this frame uses, and unseen_carry "auto" as it resolves it.
  const std::string calibration =
      pipeline::resolve_calibration(p.calibration, io::FramePattern(path));
  if (p.unseen_carry_auto) p.unseen_carry = !calibration.empty();
  const io::InputFrame f = io::open_frame(path, io::frame_number_from_name(path).value_or(0), p);
  std::cout << "file: " << path << "\n"
            << "resolution: " << f.spec.width << "x" << f.spec.height << ", " << f.spec.nchannels
            << " channels, "
            << "compression " << f.spec.get_string_attribute("compression", "?") << "\n";
  if (io::windowed(f.spec))
    std::cout << "windows: data " << f.spec.width << "x" << f.spec.height << " at (" << f.spec.x
              << ", " << f.spec.y << "), display " << f.spec.full_width << "x" << f.spec.full_height
              << " at (" << f.spec.full_x << ", " << f.spec.full_y
              << "); every data pixel is computed and written, the display image frames the "
                 "display window\n";
  if (f.spec.get_string_attribute("compression").rfind("dwa", 0) == 0)
    std::cout << "warning: DWA compression is lossy on data channels (Normal.Y, Position.Y, ...)\n";
  std::cout << "view layer: " << (f.view_layer.empty() ? "(none)" : f.view_layer) << "\n";

  // Passes: channel names grouped by everything before their last dot.
  std::map<std::string, std::vector<std::string>> passes;
  for (const auto& ch : f.spec.channelnames) {
    const auto dot = ch.rfind('.');
    passes[dot == std::string::npos ? "" : ch.substr(0, dot)].push_back(
        dot == std::string::npos ? ch : ch.substr(dot + 1));
  }
  std::cout << "passes:\n";
  for (const auto& [name, chans] : passes)
    std::cout << "  " << (name.empty() ? "(no layer)" : name) << ": " << join(chans) << "\n";

  std::cout << "G-buffer fields:\n";
  for (const auto& field : gbuffer_fields()) {
    std::cout << "  " << field << ": ";
    if (f.has(field)) {
      std::cout << join(f.wanted.at(field)) << "\n";
    } else if (!f.wanted.count(field)) {  // switched off: an empty pass name
      std::cout << "off (passes." << field << " is \"\")";
      // The AO pass is what escapes the scene when rendered with a distance beyond it.
      const bool ao = std::any_of(f.spec.channelnames.begin(), f.spec.channelnames.end(),
                                  [](const std::string& c) { return c.ends_with(".AO.R"); });
      if (field == "escape" && ao)
        std::cout << "; the frame has an AO pass: if World > Ambient Occlusion > Distance "
                     "exceeds the scene, --set passes.escape=AO lights unseen_radiance \"auto\" "
                     "by it";
      std::cout << "\n";
    } else {
      std::cout << "absent (looked for " << join(f.wanted.at(field)) << ")\n";
    }
  }

  // The pixels `run` would read, read and checked as run does: a frame whose data cannot be
  // read (truncated, damaged, a non-finite depth) fails info with run's error and exit code.
  std::vector<std::string> fields;
  try {
    fields = io::fields_needed(f, io::resolve_outputs(f, p));
  } catch (const Error& e) {
    if (e.code() != Exit::missing_pass) throw;  // reported per output below
  }
  GBuffer pixels;
  if (!fields.empty()) pixels = io::read_fields(f, fields, p);
  pixels.width = f.spec.width;
  pixels.height = f.spec.height;
  std::cout << "pixels: "
            << (fields.empty() ? "none read (no output can be computed)"
                               : "read and checked: " + join(fields))
            << "\n";

  std::cout << "camera: ";
  try {
    GBuffer g = pixels;
    const Camera c = io::find_camera(f, g, p);
    std::cout << c.source << "\n  fx " << c.fx << "  fy " << c.fy << "  cx " << c.cx << "  cy "
              << c.cy;
    if (c.reprojection_rms_px > 0)
      std::cout << "\n  reprojection RMS error " << c.reprojection_rms_px << " px";
    const Vec3d e = c.centre();
    std::cout << "\n  centre (world) " << e.x << " " << e.y << " " << e.z << "\n";
  } catch (const Error& e) {
    std::cout << "not available: " << e.what() << "\n";
  }

  std::cout << "search: " << describe_search(p, f.spec.width, f.spec.height) << "\n";
  if (f.has("emit"))
    std::cout << "emission: "
              << (io::emission_gathered(f, p)
                      ? "gathered (Emit lights other surfaces through the gather)"
                      : "direct (DiffDir already holds the light of emitting surfaces; Emit "
                        "enters the composite only)")
              << (p.emission == "auto" ? ", from the header (emission auto)" : "") << "\n";
  if (p.gather_radius_auto || p.thickness_auto || p.gather_thickness_auto) {
    std::cout << "auto: ";
    try {
      const std::string geometry = f.has("depth") ? "depth" : "position";
      const bool read = geometry == "depth" ? !pixels.depth.empty() : !pixels.position.empty();
      GBuffer g = read ? pixels : io::read_fields(f, {geometry}, p);
      std::string why;
      resolve_scene_params(p, measure_scene(g, io::find_camera(f, g, p), p), &why);
      std::cout << why << "\n";
    } catch (const Error& e) {
      std::cout << "not available: " << e.what() << "\n";
    }
  }
  if (p.unseen_radiance_auto) {
    std::cout << "unseen_radiance: ";
    try {
      if (pixels.diffcol.empty() || pixels.diffdir.empty())
        throw Error(Exit::missing_pass, "needs DiffCol and DiffDir");
      GBuffer g = pixels;
      const Camera c = io::find_camera(f, g, p);
      const ViewGBuffer v = make_view_gbuffer(g, c, p);
      const bool escape_pass = !g.escape.empty();
      const float factor = auto_unseen_factor(p.unseen_carry || escape_pass);
      const Vec3 u = mean_direct_radiance(v, g) * factor;
      std::cout << "auto = " << u.x << " " << u.y << " " << u.z << " (" << factor
                << " x the mean DiffCol x DiffDir + Emit of the frame's geometry)\n";
      if (escape_pass) {
        double sum = 0;
        size_t n = 0;
        for (size_t i = 0; i < g.escape.size(); ++i)
          if (!v.is_background(i)) sum += std::clamp(g.escape[i], 0.f, 1.f), ++n;
        std::cout << "  escape pass: " << (n ? sum / double(n) : 0.0)
                  << " of the geometry's hemisphere escapes the scene, on average (each pixel's "
                     "fill: auto x the share of its empty directions that a surface blocks)\n";
      }
      // What escapes, from the frame's background (unseen.h), over the hemisphere of a normal
      // facing up, the camera (level) and down.
      const EscapeTable escape(escape_profile(v, c, p.unseen_carry));
      std::cout << "  escape over a normal's hemisphere (each pixel's fill: auto x (1 - it); the "
                << (p.unseen_carry ? "elevations the frame does not show as open as its top "
                                     "and bottom edges say"
                                   : "elevations the frame does not show escape")
                << "): up " << escape.at(Vec3{0, -1, 0}) << ", level " << escape.at(Vec3{0, 0, -1})
                << ", down " << escape.at(Vec3{0, 1, 0}) << "\n";
    } catch (const Error& e) {
      std::cout << "not available: " << e.what() << "\n";
    }
  }
  if (p.calibration == "auto")
    std::cout << "calibration: auto = "
              << (calibration.empty() ? "none (no render of this frame in calibration/ beside it)"
                                      : calibration)
              << "\n";
  std::cout << "outputs:\n";
  for (const auto& o : known_outputs()) {
    Params one = p;
    one.outputs = {o};
    std::cout << "  " << o << ": ";
    if (o == "farfield" && p.environment.empty()) {
      std::cout << "no: needs an environment (--set environment=FILE or rgb:R,G,B)\n";
      continue;
    }
    try {
      std::cout << "yes, from " + join(io::fields_needed(f, one)) + "\n";  // throws before printing
    } catch (const Error& e) {
      std::cout << "no: " << e.what() << "\n";
    }
  }
}

}  // namespace

void add_info(CLI::App& app) {
  struct Options {
    std::string file;
    ParamOptions params;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd =
      app.add_subcommand("info",
                         "list a frame's passes, the G-buffer fields and camera found, and "
                         "which outputs can be computed");
  cmd->add_option("FILE", o->file, "one EXR frame")->required();
  o->params.add_to(*cmd);
  cmd->callback([o] { info(o->file, o->params); });
}

}  // namespace hbil::cli
