// import_povray.cpp: `hbil import-povray PASSDIR -o PATTERN`: merges the passes that
// samples/povray/render_gbuffer.sh rendered into one Blender-like multilayer EXR per frame
// (see io/povray.h), so that `hbil run` reads a POV-Ray sequence as it reads a Cycles one.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>

#include "cli/commands.h"
#include "hbil/error.h"
#include "io/camera_io.h"
#include "io/exr_output.h"
#include "io/povray.h"
#include "io/sequence.h"

namespace hbil::cli {

namespace {

struct ImportOptions {
  std::string passes;
  std::string out;
  std::string frames;
  std::string reference_dir;
  std::string view_layer = "ViewLayer";
  bool quiet = false;
};

void write_frame(const std::string& temporary, const io::ImportedFrame& f,
                 const std::string& pass_dir) {
  OIIO::ImageSpec spec(f.width, f.height, int(f.channels.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames = f.channels;
  spec.alpha_channel = -1;
  // A guard band: the frame as framed is the display window, the render the data window
  // around it (the camera, in the data window's pixels, is written for it below).
  spec.x = -f.guard_x;
  spec.y = -f.guard_y;
  spec.full_x = spec.full_y = 0;
  spec.full_width = f.width - 2 * f.guard_x;
  spec.full_height = f.height - 2 * f.guard_y;
  spec.attribute("compression", "zip");
  spec.attribute("hbil:version", HBIL_VERSION);
  spec.attribute("hbil:source", "POV-Ray passes in " + pass_dir + " (hbil import-povray)");
  if (!f.panorama) {  // a panorama's pixels are directions: no pinhole camera
    spec.attribute("hbil:camera", io::camera_json(f.camera));
    io::set_camera_attributes(spec, f.camera);
  }
  auto out = OIIO::ImageOutput::create(temporary);
  if (!out || !out->open(temporary, spec) ||
      !out->write_image(OIIO::TypeDesc::FLOAT, f.pixels.data()) || !out->close())
    throw Error(Exit::output,
                temporary + ": cannot write: " + (out ? out->geterror() : OIIO::geterror()));
}

void import_povray(const ImportOptions& o) {
  io::FramePattern out(o.out);
  std::vector<io::PovrayFrameFiles> frames = io::find_povray_frames(o.passes, o.reference_dir);
  if (!o.frames.empty()) {
    const std::vector<int> wanted = io::parse_frame_list(o.frames);
    std::vector<io::PovrayFrameFiles> kept;
    for (auto& f : frames)
      if (std::binary_search(wanted.begin(), wanted.end(), f.frame)) kept.push_back(std::move(f));
    if (kept.empty()) throw Error(Exit::input, o.passes + ": no depth pass of frames " + o.frames);
    frames = std::move(kept);
  }
  // Every frame has the same passes, or `hbil run` would find layers come and go.
  std::map<std::string, int> seen;  // pass -> a frame that has it
  for (const auto& f : frames)
    for (const auto& [pass, path] : f.passes) seen.emplace(pass, f.frame);
  for (const auto& f : frames)
    for (const auto& [pass, example] : seen)
      if (!f.passes.count(pass))
        throw Error(Exit::missing_pass, "frame " + std::to_string(f.frame) + ": no " + pass +
                                            " pass in " + o.passes + " (frame " +
                                            std::to_string(example) + " has one)");
  if (frames.size() > 1 && !out.is_sequence())
    throw Error(Exit::usage, "-o " + o.out + ": " + std::to_string(frames.size()) +
                                 " frames need a frame pattern (e.g. out/frame_####.exr)");

  // Each frame is written as a hidden temporary and renamed into place when it is complete;
  // a failure keeps the frames before it (see run.cpp).
  io::OutputBatch batch;
  std::set<std::filesystem::path> folders;
  for (const auto& f : frames) {
    batch.expect(out.path(f.frame));
    folders.insert(std::filesystem::path(out.path(f.frame)).parent_path());
  }
  bool panoramas = false;
  io::install_interrupt_cleanup();
  for (const auto& dir : folders) io::remove_stale_temporaries(dir.empty() ? "." : dir);
  try {
    for (const auto& f : frames) {
      const io::ImportedFrame img = io::import_povray_frame(f, o.view_layer);
      panoramas = panoramas || img.panorama;
      const std::string final_path = out.path(f.frame);
      const std::string tmp = io::prepare_temporary(final_path, "pov");
      batch.add(tmp, final_path);
      write_frame(tmp, img, o.passes);
      {
        const io::FrameCommit whole;
        batch.commit();
        io::note_frame_written(f.frame);
      }
      if (!o.quiet) {
        std::string layers;
        for (const auto& l : img.layers) layers += (layers.empty() ? "" : ", ") + l;
        std::cerr << "hbil: frame " << f.frame << " -> " << final_path << " (" << img.width << "x"
                  << img.height << "): " << layers << "\n";
      }
    }
  } catch (...) {
    batch.discard();
    throw;
  }
  if (!o.quiet) {
    std::cerr << "hbil: imported " << frames.size() << " frame(s); next: ";
    if (panoramas)
      std::cerr << "hbil run <shot> -o <output pattern> --set 'panorama=\"" << o.out << "\"'\n";
    else
      std::cerr << "hbil run '" << o.out << "' -o <output pattern>\n";
  }
}

}  // namespace

void add_import_povray(CLI::App& app) {
  auto o = std::make_shared<ImportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "import-povray",
      "merge the passes rendered by samples/povray/render_gbuffer.sh into Blender-like "
      "multilayer EXR frames");
  cmd->add_option("PASSDIR", o->passes,
                  "folder with depth<N>.exr, normal<N>.exr, ... and camera<N>.json")
      ->required();
  cmd->add_option("-o,--output", o->out, "output EXR frame pattern, e.g. shot/frame_####.exr")
      ->required();
  cmd->add_option("--frames", o->frames,
                  "frames to import: N, A-B, A-BxSTEP, 1,3,5-8 (default: all found)");
  cmd->add_option("--reference-dir", o->reference_dir,
                  "take reference<N>.exr from this folder instead (another radiosity render)");
  cmd->add_option("--view-layer", o->view_layer, "view layer name of the written channels")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", o->quiet, "print errors only");
  cmd->callback([o] { import_povray(*o); });
}

}  // namespace hbil::cli
