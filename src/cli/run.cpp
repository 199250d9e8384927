// run.cpp: `hbil run INPUT -o OUTPUT`: the per-frame chain over a sequence.
#include <tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli/commands.h"
#include "hbil/error.h"
#include "hbil/march.h"
#include "hbil/reduced.h"
#include "pipeline/frame_output.h"
#include "pipeline/sequence_job.h"

namespace hbil::cli {

namespace {

// "frames 1-3, 5 were written (4 of 8); the others were not", or "no frame was written".
std::string describe_written(const std::vector<int>& w, size_t total) {
  if (w.empty()) return "no frame was written";
  std::string list;
  for (size_t a = 0; a < w.size();) {
    size_t b = a;
    while (b + 1 < w.size() && w[b + 1] == w[b] + 1) ++b;
    list += (list.empty() ? "" : ", ") + std::to_string(w[a]);
    if (b > a) list += "-" + std::to_string(w[b]);
    a = b + 1;
  }
  return std::string(w.size() == 1 ? "frame " : "frames ") + list +
         (w.size() == 1 ? " was" : " were") + " written (" + std::to_string(w.size()) + " of " +
         std::to_string(total) + "); the others were not";
}

struct RunOptions {
  std::string input, output, frames, cut_frames;
  int threads = 0, preroll = 0;
  bool quiet = false, verbose = false, no_display = false;
  std::string overlap = "auto";  // on, off, auto
  ParamOptions params;
  // Display images through OpenColorIO.
  std::string display_out, display_layer, ocio_config, input_space, display, view;
};

std::string join_outputs(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

void run(const RunOptions& o) {
  pipeline::configure_heap(0, 0);  // until the first frame's size is known
  const Params requested = o.params.load();
  const pipeline::Overlap overlap = pipeline::parse_overlap(o.overlap);
  const pipeline::SequenceJob job(
      pipeline::plan_sequence(o.input, o.frames, o.preroll, o.cut_frames), requested);
  const Params& p = job.params();
  const io::InputFrame& first = job.first();
  pipeline::configure_heap(first.spec.width, first.spec.height);
  if (!o.quiet) {
    std::cerr << "hbil: outputs: " << join_outputs(p.outputs) << "\n";
    if (!job.why_dropped().empty())
      std::cerr << "hbil: outputs \"auto\" left out what the input cannot give: "
                << job.why_dropped() << "\n";
    if (!job.scene_description().empty())
      std::cerr << "hbil: auto: " << job.scene_description() << "\n";
    if (p.method == "bitmask") {
      std::ostringstream s;
      s << "hbil: bitmask thickness: ";
      if (first.has("backdepth"))
        s << "per pixel from " << first.spec.channelnames[first.channels.at("backdepth")[0]] << " ("
          << p.thickness << " where it has no back face)";
      else
        s << p.thickness << " world units"
          << (p.thickness_growth > 0 ? " + " + std::to_string(p.thickness_growth) + " x depth"
                                     : std::string())
          << (first.wanted.count("backdepth")
                  ? " (no back-face channel " + p.passes.at("backdepth").dump() + ")"
                  : std::string(" (passes.backdepth is off)"));
      std::cerr << s.str() << "\n";
    }
    std::cerr << "hbil: march: " << p.method << ", "
              << (p.vectorised ? std::string("SIMD, ") + march_simd_target()
                               : std::string("scalar reference"))
              << "\n";
    std::cerr << "hbil: search: " << describe_search(p, first.spec.width, first.spec.height)
              << "\n";
  }
  // Outputs and display images: settings checked before any frame is computed.
  pipeline::FrameOutput output(
      {o.output, o.no_display, o.display_out, o.display_layer,
       io::DisplaySettings{o.ocio_config, o.input_space, o.display, o.view}},
      job);
  if (!o.quiet && !output.describe_display().empty())
    std::cerr << "hbil: display images " << output.describe_display() << "\n";
  std::unique_ptr<tbb::global_control> threads;
  if (o.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    o.threads);
  const bool tty = isatty(STDERR_FILENO);
  const char* clear = tty ? "\r\033[K" : "";
  const size_t nframes = job.plan().frames.size(), npreroll = job.plan().preroll.size();
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();

  // Each frame's files are renamed into place as soon as they are complete (frame_output.h);
  // an interrupt removes the temporaries in flight, and a killed run's are removed here.
  io::install_interrupt_cleanup();
  if (const int stale = output.remove_stale(); stale > 0 && !o.quiet)
    std::cerr << "hbil: removed " << stale << " temporary file" << (stale == 1 ? "" : "s")
              << " left by a run that was killed\n";
  pipeline::SequenceJob::Hooks hooks;
  hooks.deliver = [&](pipeline::FrameResult& r) { output.write(r); };
  hooks.delivered = [&](const pipeline::FrameResult& r) {
    if (o.verbose) {
      char line[256];
      std::snprintf(
          line, sizeof line,
          "hbil: frame %d: read %.0f ms, camera %.0f ms, compute %.0f ms, write %.0f ms\n", r.frame,
          r.times.read_ms, r.times.camera_ms, r.times.compute_ms, r.times.deliver_ms);
      std::cerr << clear << line;
    }
    if (!o.quiet) {
      std::string history;
      if (r.temporal && !r.report.first && !r.report.cut) {
        char h[96];
        std::snprintf(h, sizeof h, "  history %.0f %% (%s)", 100 * r.report.history,
                      r.report.reprojection.c_str());
        history = h;
      }
      char line[512];
      std::snprintf(line, sizeof line, "hbil: frame %d (%zu/%zu) %.3f s  camera: %s%s", r.frame,
                    r.index, nframes,
                    std::chrono::duration<double>(Clock::now() - r.started).count(),
                    r.camera.source.c_str(), history.c_str());
      std::cerr << clear << line << (tty ? "" : "\n") << std::flush;
    }
  };
  hooks.cut = [&](int frame, const TemporalReport& rep) {
    if (!o.quiet)
      std::cerr << clear << "hbil: frame " << frame << ": cut (" << rep.cut_reason
                << "), history dropped\n";
  };
  // Warnings are printed with --quiet too: they say something about the result.
  hooks.warning = [&](int, const std::string& message) {
    std::cerr << clear << "hbil: warning: " << message << "\n";
  };
  hooks.preroll_done = [&](int frame, size_t k, size_t n, double seconds) {
    if (o.quiet) return;
    char line[256];
    std::snprintf(line, sizeof line, "hbil: frame %d (pre-roll %zu/%zu) %.3f s", frame, k, n,
                  seconds);
    std::cerr << clear << line << (tty ? "" : "\n") << std::flush;
  };
  try {
    job.run(hooks, overlap);
  } catch (...) {
    if (tty && !o.quiet) std::cerr << "\n";
    output.discard();
    // Printed with --quiet too: which frames a rerun still needs.
    const std::vector<int>& w = output.written();
    std::cerr << "hbil: " << describe_written(w, nframes) << "\n";
    throw;
  }
  const double total = std::chrono::duration<double>(Clock::now() - start).count();
  if (!o.quiet) {
    char line[256];
    const std::string pre = npreroll == 0 ? "" : " (+" + std::to_string(npreroll) + " pre-roll)";
    std::snprintf(line, sizeof line, "hbil: %zu frames%s, %.3f s per frame, %.2f s in all", nframes,
                  pre.c_str(), total / double(nframes + npreroll), total);
    std::cerr << (tty ? "\n" : "") << line << "\n";
  }
}

}  // namespace

void add_run(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd =
      app.add_subcommand("run", "compute the requested layers for every frame of a sequence");
  cmd->add_option("INPUT", o->input,
                  "input EXR: a frame pattern (frame_####.exr, frame_%04d.exr) or one file")
      ->required();
  cmd->add_option("-o,--output", o->output,
                  "output EXR: a frame pattern or one file; folders are created")
      ->required();
  cmd->add_option("--frames", o->frames,
                  "frame range A-B, or one frame N (default: every frame found)");
  cmd->add_option("--preroll", o->preroll,
                  "temporal chain: compute the P frames before the first one first (not written), "
                  "so that a farm chunk starts with history")
      ->check(count_check("0 or a positive number of frames"));
  cmd->add_option("--cut-frames", o->cut_frames,
                  "temporal chain: frames that start a new shot (history dropped), e.g. 12,40; "
                  "cuts are also detected");
  cmd->add_option(
         "--overlap", o->overlap,
         "read the next frame and write the previous one while a frame computes: on, off, or auto "
         "(on up to 4.2 megapixels, off above, to hold one frame in memory)")
      ->default_val("auto")
      ->check(CLI::IsMember({"on", "off", "auto"}));
  cmd->add_option("--threads", o->threads,
                  "worker threads (0 = all cores); results are identical for any count")
      ->default_val(0)
      ->check(count_check(kThreadsMeaning));
  cmd->add_flag("-q,--quiet", o->quiet, "no progress lines and no summary");
  cmd->add_flag(
      "-v,--verbose", o->verbose,
      "also print the time each frame spends reading, finding the camera, computing and writing");
  cmd->add_option("--display-out", o->display_out,
                  "display image per frame (.png, .jpg, .exr; frame pattern) through OpenColorIO; "
                  "default: OUTPUT with .png when composite (or --display-layer) is computed");
  cmd->add_flag("--no-display", o->no_display, "write no display images");
  cmd->add_option(
      "--display-layer", o->display_layer,
      "layer shown in the display image: composite (default when computed), ao, irradiance, "
      "indirect, farfield");
  cmd->add_option("--display", o->display,
                  "OCIO display (default: the config's default, sRGB in the shipped one)");
  cmd->add_option("--view", o->view,
                  "OCIO view (default: the display's default, Standard in the shipped one)");
  cmd->add_option("--input-space", o->input_space,
                  "OCIO colour space of the pixels (default: the preset's input_space, else the "
                  "scene_linear role)");
  cmd->add_option("--ocio-config", o->ocio_config,
                  "OCIO config file; default $OCIO, else the config shipped with hbil "
                  "(presets/ocio/hbil.ocio)");
  o->params.add_to(*cmd);
  cmd->callback([o] { run(*o); });
}

}  // namespace hbil::cli
