// run.cpp: `hbil run INPUT -o OUTPUT`: the per-frame chain over a sequence.
#include <malloc.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <future>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "cli/commands.h"
#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "hbil/march.h"
#include "hbil/reduced.h"
#include "hbil/temporal.h"
#include "io/display.h"
#include "io/environment.h"
#include "io/exr_frame.h"
#include "io/exr_output.h"
#include "io/sequence.h"

namespace hbil::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RunOptions {
  std::string input, output, frames, cut_frames;
  int threads = 0, preroll = 0;
  bool quiet = false, verbose = false, no_display = false;
  std::string overlap = "auto";  // on, off, auto
  ParamOptions params;
  // Display images through OpenColorIO.
  std::string display_out, display_layer, ocio_config, input_space, display, view;
};

// The frames to write and their input and output paths; the pre-roll frames computed
// before them (temporal chain) and the frames given as cuts.
struct Job {
  std::vector<int> frames;
  io::FramePattern in, out;
  std::vector<int> preroll;
  std::set<int> cuts;
};

// "12,40" -> {12, 40}.
std::set<int> parse_cut_frames(const std::string& text) {
  std::set<int> cuts;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) {
    try {
      size_t used = 0;
      const int f = std::stoi(item, &used);
      if (used != item.size() || f < 0) throw std::invalid_argument(item);
      cuts.insert(f);
    } catch (const std::exception&) {
      throw Error(Exit::usage,
                  "--cut-frames: \"" + item + "\" is not a frame number (expected e.g. 12,40)");
    }
  }
  return cuts;
}

Job plan(const RunOptions& o) {
  Job job{{}, io::FramePattern(o.input), io::FramePattern(o.output), {}, {}};
  if (!job.in.is_sequence()) {
    if (!o.frames.empty())
      throw Error(Exit::usage,
                  "--frames needs an input frame pattern, got the single file " + o.input);
    job.frames = {io::frame_number_from_name(o.input).value_or(0)};
  } else if (!o.frames.empty()) {
    const io::FrameRange r = io::parse_frame_range(o.frames);
    for (int f = r.first; f <= r.last; ++f) job.frames.push_back(f);
  } else {
    job.frames = job.in.existing_frames();
    if (job.frames.empty())
      throw Error(Exit::input, o.input + ": no frames found matching the pattern");
  }
  if (job.frames.size() > 1 && !job.out.is_sequence())
    throw Error(Exit::usage, "-o " + o.output + ": a sequence of " +
                                 std::to_string(job.frames.size()) +
                                 " frames needs an output frame pattern (e.g. out/frame_####.exr)");
  for (int f : job.frames) {
    std::error_code ec;
    if (fs::equivalent(job.in.path(f), job.out.path(f), ec))
      throw Error(Exit::usage, "-o " + job.out.path(f) + " would overwrite its own input");
  }
  if (o.preroll > 0) {
    if (!job.in.is_sequence())
      throw Error(Exit::usage,
                  "--preroll needs an input frame pattern, got the single file " + o.input);
    // The frames of the sequence that exist in [first − P, first − 1].
    const int first = job.frames.front();
    for (int f : job.in.existing_frames())
      if (f >= first - o.preroll && f < first) job.preroll.push_back(f);
  }
  if (!o.cut_frames.empty()) job.cuts = parse_cut_frames(o.cut_frames);
  return job;
}

// The config shipped with hbil: installed beside the binary, else in the source tree.
std::string shipped_ocio_config() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path installed = exe.parent_path().parent_path() / "share/hbil/ocio/hbil.ocio";
  if (!ec && fs::exists(installed)) return installed.string();
  return HBIL_OCIO_CONFIG;
}

// The pixels of a display layer: 1 (ao), 3 or 4 (composite) channels; the frame's own
// buffer where it is stored that way, else `scratch` filled.
const std::vector<float>& display_pixels(const AoFrame& f, const std::string& layer, int& channels,
                                         std::vector<float>& scratch) {
  const size_t n = size_t(f.width) * f.height;
  if (layer == "composite") {
    channels = 4;
    scratch.resize(n * 4);
    for (size_t i = 0; i < n; ++i) {
      const Vec3& c = f.composite[i];
      float* px = &scratch[4 * i];
      px[0] = c.x, px[1] = c.y, px[2] = c.z;
      px[3] = f.composite_alpha.empty() ? 1.f : f.composite_alpha[i];
    }
    return scratch;
  }
  if (layer == "ao" && f.ao_rgb.empty()) {
    channels = 1;
    return f.ao;
  }
  const std::vector<Vec3>& v = layer == "ao"           ? f.ao_rgb
                               : layer == "irradiance" ? f.irradiance
                               : layer == "indirect"   ? f.indirect
                                                       : f.farfield;
  channels = 3;
  scratch.resize(n * 3);
  for (size_t i = 0; i < n; ++i)
    scratch[3 * i] = v[i].x, scratch[3 * i + 1] = v[i].y, scratch[3 * i + 2] = v[i].z;
  return scratch;
}

std::string join_outputs(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

void run(const RunOptions& o) {
  // glibc serves buffers above its heap threshold from mmap and returns them to the system
  // when they are freed; smaller ones stay in its heaps for reuse. The threshold is fixed here
  // (glibc's own moves up to 32 MiB as buffers are freed): at 32 MiB where a frame's RGB
  // float plane fits below it, with the heaps trimmed only above 64 MiB free (glibc's rule
  // there), so that frame buffers are reused without page faults; at 1 MiB where it does not
  // (3840x2160 and up: those planes are mapped and unmapped every frame anyway), so that the
  // smaller buffers are returned too and add nothing to the run's peak memory. 1 MiB until
  // the first frame's size is known.
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
  const Params requested = o.params.load();
  const Job job = plan(o);
  // Outputs "auto" are resolved once, on the first frame's header: every frame then writes
  // the same layers, and a later frame that lacks a pass is an error.
  std::string why_dropped;
  const io::InputFrame first =
      io::open_frame(job.in.path(job.frames.front()), job.frames.front(), requested);
  const Params p = io::resolve_outputs(first, requested, &why_dropped);
  constexpr size_t kHeapMax = size_t(32) << 20;
  if (size_t(first.spec.width) * size_t(first.spec.height) * sizeof(Vec3) <= kHeapMax) {
    mallopt(M_MMAP_THRESHOLD, int(kHeapMax));
    mallopt(M_TRIM_THRESHOLD, int(2 * kHeapMax));  // what glibc's own rule would reach
  }
  if (!o.quiet) {
    std::cerr << "hbil: outputs: " << join_outputs(p.outputs) << "\n";
    if (!why_dropped.empty())
      std::cerr << "hbil: outputs \"auto\" left out what the input cannot give: " << why_dropped
                << "\n";
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
  // Far field: the environment is projected to SH once for the whole run.
  std::optional<SH9> environment;
  if (!p.environment.empty()) environment = io::load_environment(p.environment);
  // Display images: settings checked before any frame is computed.
  std::optional<io::DisplayTransform> display;
  std::optional<io::FramePattern> display_pattern;
  std::string display_layer = o.display_layer;
  // Without --display-out, a PNG of the composite (or of --display-layer) goes beside each
  // EXR, unless --no-display.
  std::string display_out = o.display_out;
  if (display_out.empty() && !o.no_display && (p.wants("composite") || !display_layer.empty()))
    display_out = fs::path(o.output).replace_extension(".png").string();
  if (!display_out.empty() && o.no_display)
    throw Error(Exit::usage, "--display-out and --no-display contradict each other");
  if (!display_out.empty()) {
    if (!io::is_display_image_path(display_out))
      throw Error(Exit::usage,
                  "--display-out " + display_out + ": use a .png, .jpg, .jpeg or .exr name");
    if (display_layer.empty())
      display_layer = p.wants("composite") ? "composite" : p.outputs.front();
    if (display_layer == "bentcone" || display_layer == "history" || !p.wants(display_layer))
      throw Error(Exit::usage,
                  "--display-layer " + display_layer +
                      ": must be one of the computed colour layers (ao, irradiance, indirect, "
                      "farfield, composite) named in outputs");
    display.emplace(
        io::DisplaySettings{o.ocio_config, o.input_space.empty() ? p.input_space : o.input_space,
                            o.display, o.view},
        shipped_ocio_config());
    display_pattern.emplace(display_out);
    if (job.frames.size() > 1 && !display_pattern->is_sequence())
      throw Error(Exit::usage,
                  "--display-out " + display_out + ": a sequence needs a frame pattern");
    for (int f : job.frames)
      if (display_pattern->path(f) == job.out.path(f))
        throw Error(Exit::usage, "--display-out " + display_out + " is the EXR output's name");
    if (!o.quiet)
      std::cerr << "hbil: display images " << display_out << " (" << display_layer
                << "): " << display->describe() << "\n";
  }
  std::unique_ptr<tbb::global_control> threads;
  if (o.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    o.threads);
  const bool tty = isatty(STDERR_FILENO);

  // Finished frames wait as hidden temporaries and are renamed into place only when every
  // frame succeeded: a failed run leaves the output folder as it was.
  io::OutputBatch batch;
  for (int f : job.frames) {
    batch.expect(job.out.path(f));
    if (display_pattern) batch.expect(display_pattern->path(f));
  }
  const auto start = Clock::now();
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  // A frame as read: header, fields and camera, with the time each took.
  struct Loaded {
    io::InputFrame in;
    GBuffer g;
    Camera cam;
    double read_ms = 0, camera_ms = 0;
  };
  auto load = [&](int frame) {
    const auto t0 = Clock::now();
    Loaded l;
    l.in = io::open_frame(job.in.path(frame), frame, p);
    // Colour fields stored as half stay half until the frame's geometry is done with.
    l.g = io::read_fields(l.in, io::fields_needed(l.in, p), p, true);
    const auto t_read = Clock::now();
    l.cam = io::find_camera(l.in, l.g, p);
    l.read_ms = ms(t0, t_read);
    l.camera_ms = ms(t_read, Clock::now());
    return l;
  };
  // What is printed of a frame once its files are written.
  struct Written {
    int frame = 0;
    size_t index = 0;
    double read_ms = 0, camera_ms = 0, compute_ms = 0, write_ms = 0;
    std::string camera, history;
    Clock::time_point started;
  };
  auto report = [&](const Written& w) {
    if (o.verbose) {
      char line[256];
      std::snprintf(
          line, sizeof line,
          "hbil: frame %d: read %.0f ms, camera %.0f ms, compute %.0f ms, write %.0f ms\n", w.frame,
          w.read_ms, w.camera_ms, w.compute_ms, w.write_ms);
      std::cerr << (tty ? "\r\033[K" : "") << line;
    }
    if (!o.quiet) {
      char line[512];
      std::snprintf(line, sizeof line, "hbil: frame %d (%zu/%zu) %.3f s  camera: %s%s", w.frame,
                    w.index, job.frames.size(),
                    std::chrono::duration<double>(Clock::now() - w.started).count(),
                    w.camera.c_str(), w.history.c_str());
      std::cerr << (tty ? "\r\033[K" : "") << line << (tty ? "" : "\n") << std::flush;
    }
  };
  try {
    // Pre-roll frames first (computed, not written), then the frames to write.
    std::vector<int> order = job.preroll;
    order.insert(order.end(), job.frames.begin(), job.frames.end());
    const bool temporal = p.temporal && order.size() > 1;
    std::optional<TemporalChain> chain;
    if (temporal) chain.emplace(p);
    // With the overlap, frame k+1 is read and frame k−1 written while frame k is computed
    // (about 13 % faster at 3840x2160 on 2 cores; three frames in memory);
    // without it each frame is read, computed and written in turn, so that one frame is in
    // memory. "auto" overlaps up to 2^22 pixels (2560x1440 and below). Each stage keeps the
    // frame order, so the output bytes are the same either way.
    const bool overlap =
        o.overlap == "on" ||
        (o.overlap == "auto" &&
         size_t(first.spec.width) * size_t(first.spec.height) <= (size_t(1) << 22));
    std::future<Loaded> next = std::async(std::launch::async, load, order.front());
    std::future<Written> writing;  // the previous frame's files
    std::string first_path;
    int width = 0, height = 0;
    for (size_t k = 0; k < order.size(); ++k) {
      const auto t0 = Clock::now();
      const int frame = order[k];
      const bool preroll = k < job.preroll.size();
      Loaded cur = next.get();
      auto read_next = [&] {
        if (k + 1 < order.size()) next = std::async(std::launch::async, load, order[k + 1]);
      };
      if (overlap) read_next();
      const io::InputFrame& in = cur.in;
      if (k == 0) {
        width = in.spec.width;
        height = in.spec.height;
        first_path = in.path;
      } else if (in.spec.width != width || in.spec.height != height) {
        throw Error(Exit::bad_data, in.where() + ": resolution " + std::to_string(in.spec.width) +
                                        "x" + std::to_string(in.spec.height) + " differs from " +
                                        std::to_string(width) + "x" + std::to_string(height) +
                                        " of " + first_path);
      }
      const auto t_compute = Clock::now();
      TemporalReport rep;
      AoFrame result =
          chain ? chain->process(std::move(cur.g), cur.cam, frame, job.cuts.count(frame) > 0,
                                 environment ? &*environment : nullptr, &rep)
                : (cur.g.unpack(),
                   compute_ao_frame(cur.g, cur.cam, p, environment ? &*environment : nullptr));
      const double compute_ms = ms(t_compute, Clock::now());
      if (!overlap && preroll) read_next();
      if (rep.cut) {
        const std::string line = "hbil: frame " + std::to_string(frame) + ": cut (" +
                                 rep.cut_reason + "), history dropped";
        if (!o.quiet) std::cerr << (tty ? "\r\033[K" : "") << line << "\n";
      }
      if (preroll) {
        if (!o.quiet) {
          char line[256];
          std::snprintf(line, sizeof line, "hbil: frame %d (pre-roll %zu/%zu) %.3f s", frame, k + 1,
                        job.preroll.size(),
                        std::chrono::duration<double>(Clock::now() - t0).count());
          std::cerr << (tty ? "\r\033[K" : "") << line << (tty ? "" : "\n") << std::flush;
        }
        continue;
      }
      Written w{frame,
                k + 1 - job.preroll.size(),
                cur.read_ms,
                cur.camera_ms,
                compute_ms,
                0,
                cur.cam.source,
                "",
                t0};
      if (chain && !rep.first && !rep.cut) {
        char h[96];
        std::snprintf(h, sizeof h, "  history %.0f %% (%s)", 100 * rep.history,
                      rep.reprojection.c_str());
        w.history = h;
      }
      if (writing.valid()) report(writing.get());  // the previous frame's files
      // The input's header and the camera go with the frame to its writer.
      writing = std::async(std::launch::async, [&, w, result = std::move(result), spec = in.spec,
                                                cam = cur.cam]() mutable {
        const auto t_write = Clock::now();
        const std::string out_path = job.out.path(w.frame);
        // The display image is written beside the EXR, on a thread of its own (PNG's deflate
        // runs on one core). Whatever either write leaves goes into the batch before an error
        // is passed on, so that a failed run removes it.
        std::future<std::string> shown;
        const std::string shown_path = display ? display_pattern->path(w.frame) : "";
        if (display)
          shown = std::async(std::launch::async, [&] {
            int channels = 0;
            std::vector<float> scratch;
            const std::vector<float>& px = display_pixels(result, display_layer, channels, scratch);
            return io::write_display_temporary(
                shown_path, px, channels, result.width, result.height, *display,
                "hbil " + display_layer + ", frame " + std::to_string(w.frame));
          });
        std::exception_ptr failed;
        try {
          batch.add(io::write_temporary(out_path, result, spec, p, cam), out_path);
        } catch (...) {
          failed = std::current_exception();
        }
        if (shown.valid()) {
          try {
            batch.add(shown.get(), shown_path);
          } catch (...) {
            if (!failed) failed = std::current_exception();
          }
        }
        if (failed) std::rethrow_exception(failed);
        w.write_ms = ms(t_write, Clock::now());
        return w;
      });
      if (!overlap) {
        report(writing.get());
        read_next();
      }
    }
    if (writing.valid()) report(writing.get());
    batch.commit();
  } catch (...) {
    if (tty && !o.quiet) std::cerr << "\n";
    batch.discard();
    throw;
  }
  const double total = std::chrono::duration<double>(Clock::now() - start).count();
  if (!o.quiet) {
    char line[256];
    const size_t computed = job.frames.size() + job.preroll.size();
    const std::string pre =
        job.preroll.empty() ? "" : " (+" + std::to_string(job.preroll.size()) + " pre-roll)";
    std::snprintf(line, sizeof line, "hbil: %zu frames%s, %.3f s per frame, %.2f s in all",
                  job.frames.size(), pre.c_str(), total / double(computed), total);
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
      ->check(CLI::NonNegativeNumber);
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
      ->check(CLI::NonNegativeNumber);
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
