// run.cpp: `hbil run INPUT -o OUTPUT`: the per-frame chain over a sequence.
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>

#include "cli/commands.h"
#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "hbil/march.h"
#include "hbil/reduced.h"
#include "io/run_log.h"
#include "pipeline/frame_output.h"
#include "pipeline/sequence_job.h"

namespace hbil::cli {

namespace {

// "1-3, 5" for {1, 2, 3, 5}.
std::string frame_list(const std::vector<int>& w) {
  std::string list;
  for (size_t a = 0; a < w.size();) {
    size_t b = a;
    while (b + 1 < w.size() && w[b + 1] == w[b] + 1) ++b;
    list += (list.empty() ? "" : ", ") + std::to_string(w[a]);
    if (b > a) list += "-" + std::to_string(w[b]);
    a = b + 1;
  }
  return list;
}

// "frames 1-3, 5 were written (4 of 8); the others were not", or "no frame was written".
std::string describe_written(const std::vector<int>& w, size_t total) {
  if (w.empty()) return "no frame was written";
  return std::string(w.size() == 1 ? "frame " : "frames ") + frame_list(w) +
         (w.size() == 1 ? " was" : " were") + " written (" + std::to_string(w.size()) + " of " +
         std::to_string(total) + "); the others were not";
}

struct RunOptions {
  std::string input, output, frames, cut_frames, log_json;
  int threads = 0, preroll = 0;
  bool quiet = false, verbose = false, no_display = false, skip_existing = false;
  std::string overlap = "auto";  // on, off, auto
  ParamOptions params;
  // Display images through OpenColorIO.
  std::string display_out, display_layer, ocio_config, input_space, display, view;
};

// The time now in UTC, ISO 8601 to the second.
std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string join_outputs(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// `written`: the frames in place so far, for the run log's "end" line.
void run_frames(const RunOptions& o, io::RunLog& log, int& written) {
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
    if (p.unseen_radiance_auto && gathers(p) && first.has("escape"))
      std::cerr << "hbil: unseen_radiance auto: per frame, " << auto_unseen_factor(true)
                << " x the mean DiffCol x DiffDir + Emit of its geometry, in the directions the"
                   " search finds empty, times the share of them that a surface blocks by "
                << first.spec.channelnames[first.channels.at("escape")[0]]
                << " (passes.escape: what escapes the whole scene)"
                << (p.radiance_cache > 0 || !p.panorama.empty()
                        ? "; where a radiance cache or a panorama knows what lies off screen, "
                          "what it shows"
                        : "")
                << "\n";
    else if (p.unseen_radiance_auto && gathers(p))
      std::cerr << "hbil: unseen_radiance auto: per frame, " << auto_unseen_factor(p.unseen_carry)
                << " x the mean DiffCol x DiffDir + Emit of its geometry, times 1 - what its"
                   " background says escapes over each pixel's hemisphere, "
                << (p.unseen_carry
                        ? "the elevations it does not show as open as its top and bottom edges say"
                        : "the elevations it does not show escaping")
                << " (hbil info FRAME prints both)\n";
    if (requested.calibration == "auto" && !p.calibration.empty() && gathers(p))
      std::cerr << "hbil: calibration auto: " << p.calibration << "\n";
    if (requested.calibration != "auto" && !p.calibration.empty() && !gathers(p))
      std::cerr << "hbil: calibration left unused: the outputs gather no light (irradiance, "
                   "indirect or composite)\n";
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
    std::cerr << "hbil: slices: " << p.slices << " a pixel"
              << (!p.slices_auto  ? ""
                  : p.slices == 1 ? " (auto, a temporal chain: 2 on a frame without history)"
                                  : " (auto, no temporal chain)")
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
  const size_t n_threads =
      o.threads > 0 ? size_t(o.threads) : size_t(tbb::info::default_concurrency());
  {
    const std::vector<int>& frames = job.plan().frames;
    log.write("start", {{"time", utc_now()},
                        {"hbil", HBIL_VERSION},
                        {"input", o.input},
                        {"output", o.output},
                        {"frames", frames},
                        {"preroll", job.plan().preroll.size()},
                        {"outputs", p.outputs},
                        {"resolution", {first.spec.width, first.spec.height}},
                        {"threads", n_threads},
                        {"pid", getpid()}});
  }
  const bool tty = isatty(STDERR_FILENO);
  const char* clear = tty ? "\r\033[K" : "";
  const size_t nframes = job.plan().frames.size(), npreroll = job.plan().preroll.size();
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  // When each frame was finished (its files in place, or computed for the pre-roll or the
  // history alone): the time from the first to the last, a frame at a time, is the rate of a
  // long shot, without the start-up and the first frame's reading, which the whole run's rate
  // holds once. (Frames are written on a thread of their own: a lock.)
  std::mutex finish_lock;
  Clock::time_point first_finished{}, last_finished{};
  size_t finished = 0;
  auto finish = [&] {
    const std::lock_guard<std::mutex> lock(finish_lock);
    last_finished = Clock::now();
    if (finished++ == 0) first_finished = last_finished;
  };

  // Each frame's files are renamed into place as soon as they are complete (frame_output.h);
  // an interrupt removes the temporaries in flight, and a killed run's are removed here.
  io::install_interrupt_cleanup();
  if (const int stale = output.remove_stale(); stale > 0 && !o.quiet)
    std::cerr << "hbil: removed " << stale << " temporary file" << (stale == 1 ? "" : "s")
              << " left by a run that was killed\n";
  // --skip-existing: the frames whose files this job already made, complete.
  std::set<int> done;
  if (o.skip_existing) {
    std::vector<int> skipped;
    std::string why;
    for (int f : job.plan().frames) {
      std::string why_f;
      if (output.done(f, &why_f)) {
        done.insert(f);
        skipped.push_back(f);
      } else if (why.empty()) {
        why = why_f;
      }
    }
    log.write("skip", {{"frames", skipped}});
    if (!o.quiet) {
      if (skipped.empty())
        std::cerr << "hbil: skip-existing: no frame is done yet (" << why << ")\n";
      else
        std::cerr << "hbil: skip-existing: " << (skipped.size() == 1 ? "frame " : "frames ")
                  << frame_list(skipped) << " done by this job, not written again"
                  << (skipped.size() < nframes ? "; the first to make: " + why : "") << "\n";
    }
  }
  pipeline::SequenceJob::Hooks hooks;
  // The frame's log line is written as its files are in place (FrameOutput::write), so that
  // an interrupt's "end" line never counts a frame the lines before it do not hold.
  hooks.deliver = [&](pipeline::FrameResult& r) {
    const auto writing = Clock::now();
    output.write(r, [&] {
      ++written;
      if (!log.enabled()) return;
      const bool history = r.temporal && !r.report.first && !r.report.cut;
      auto files = nlohmann::ordered_json::array({output.path(r.frame)});
      if (!output.display_path(r.frame).empty()) files.push_back(output.display_path(r.frame));
      log.write(
          "frame",
          {{"frame", r.frame},
           {"index", r.index},
           {"of", nframes},
           {"seconds", std::chrono::duration<double>(Clock::now() - r.started).count()},
           {"read_ms", r.times.read_ms},
           {"camera_ms", r.times.camera_ms},
           {"compute_ms", r.times.compute_ms},
           {"write_ms", std::chrono::duration<double, std::milli>(Clock::now() - writing).count()},
           {"camera", r.camera.source},
           {"cut", r.report.cut ? nlohmann::ordered_json(r.report.cut_reason) : nullptr},
           {"history", history ? nlohmann::ordered_json(r.report.history) : nullptr},
           {"reprojection", history ? nlohmann::ordered_json(r.report.reprojection) : nullptr},
           {"files", files}});
    });
    finish();
  };
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
  hooks.warning = [&](int frame, const std::string& message) {
    std::cerr << clear << "hbil: warning: " << message << "\n";
    log.write("warning", {{"frame", frame}, {"message", message}});
  };
  hooks.preroll_done = [&](int frame, size_t k, size_t n, double seconds) {
    finish();
    log.write("preroll", {{"frame", frame}, {"index", k}, {"of", n}, {"seconds", seconds}});
    if (o.quiet) return;
    char line[256];
    std::snprintf(line, sizeof line, "hbil: frame %d (pre-roll %zu/%zu) %.3f s", frame, k, n,
                  seconds);
    std::cerr << clear << line << (tty ? "" : "\n") << std::flush;
  };
  hooks.calibrated = [&](const pipeline::CalibrationPoint& c) {
    log.write("calibration", {{"frame", c.frame},
                              {"file", c.path},
                              {"reference_mean", c.reference},
                              {"mean_without_fill", c.without},
                              {"mean_with_fill", c.with},
                              {"unseen_scale", c.scale},
                              {"tiles", {c.tiles.cols, c.tiles.rows}},
                              {"tile_factors", c.tiles.factor},
                              {"seconds", c.seconds}});
    if (o.quiet) return;
    char line[512], tiles[128] = "";
    if (c.tiles.cols > 0) {
      const auto [lo, hi] = std::minmax_element(c.tiles.factor.begin(), c.tiles.factor.end());
      std::snprintf(tiles, sizeof tiles, "; %d x %d tiles, %.2f-%.2f x", c.tiles.cols, c.tiles.rows,
                    double(*lo), double(*hi));
    }
    if (c.reaches)
      std::snprintf(line, sizeof line,
                    "hbil: calibration, frame %d: unseen_scale %.3f (mean DiffCol x DiffInd "
                    "%.5f; hbil's indirect %.5f without the fill, %.5f with it%s), %.3f s\n",
                    c.frame, c.scale, c.reference, c.without, c.with, tiles, c.seconds);
    else
      std::snprintf(line, sizeof line,
                    "hbil: calibration, frame %d: the fill reaches no pixel, unseen_scale 1 "
                    "(mean DiffCol x DiffInd %.5f; hbil's indirect %.5f), %.3f s\n",
                    c.frame, c.reference, c.without, c.seconds);
    std::cerr << clear << line;
  };
  hooks.history_only = [&](int frame, double seconds) {
    finish();
    log.write("history", {{"frame", frame}, {"seconds", seconds}});
    if (o.quiet) return;
    char line[256];
    std::snprintf(line, sizeof line, "hbil: frame %d (done, computed for the history) %.3f s",
                  frame, seconds);
    std::cerr << clear << line << (tty ? "" : "\n") << std::flush;
  };
  try {
    job.run(hooks, overlap, nullptr, done);
  } catch (...) {
    if (tty && !o.quiet) std::cerr << "\n";
    output.discard();
    // Printed with --quiet too: which frames a rerun still needs.
    const std::vector<int>& w = output.written();
    std::cerr << "hbil: " << describe_written(w, nframes - done.size())
              << (done.empty() ? "" : " (" + std::to_string(done.size()) + " were done before)")
              << "\n";
    throw;
  }
  const double total = std::chrono::duration<double>(Clock::now() - start).count();
  const double after_first =
      finished < 2 ? 0
                   : std::chrono::duration<double>(last_finished - first_finished).count() /
                         double(finished - 1);
  log.write("end", {{"exit", 0},
                    {"written", written},
                    {"skipped", done.size()},
                    {"seconds", total},
                    {"seconds_per_frame", total / double(nframes + npreroll)},
                    {"seconds_per_frame_after_first",  // null below 2 frames finished
                     finished < 2 ? nlohmann::ordered_json(nullptr)
                                  : nlohmann::ordered_json(after_first)}});
  if (!o.quiet) {
    char line[320];
    const std::string pre = npreroll == 0 ? "" : " (+" + std::to_string(npreroll) + " pre-roll)";
    const std::string skipped =
        done.empty() ? "" : " (" + std::to_string(done.size()) + " done before, not written)";
    char rate[96] = "";
    if (finished >= 2)
      std::snprintf(rate, sizeof rate, "; %.3f s a frame after the first", after_first);
    std::snprintf(line, sizeof line, "hbil: %zu frame%s%s%s, %.3f s per frame, %.2f s in all%s",
                  nframes, nframes == 1 ? "" : "s", pre.c_str(), skipped.c_str(),
                  total / double(nframes + npreroll), total, rate);
    std::cerr << (tty ? "\n" : "") << line << "\n";
  }
}

void run(const RunOptions& o) {
  io::RunLog log;
  if (!o.log_json.empty()) log.open(o.log_json);
  int written = 0;
  // The failure itself is what the caller reports: a log that cannot take its last line
  // does not replace it.
  auto end = [&](Exit code, const std::string& message) noexcept {
    try {
      log.write("end", {{"exit", int(code)}, {"written", written}, {"error", message}});
    } catch (...) {
    }
  };
  try {
    run_frames(o, log, written);
  } catch (const Error& e) {
    end(e.code(), e.what());
    throw;
  } catch (const std::exception& e) {
    end(Exit::failure, std::string("internal error: ") + e.what());
    throw;
  }
}

// The options of `run` on `cmd`, into `o`.
void add_run_options(CLI::App* cmd, const std::shared_ptr<RunOptions>& o) {
  cmd->add_option("INPUT", o->input,
                  "input EXR: a frame pattern (frame_####.exr, frame_%04d.exr) or one file")
      ->required();
  cmd->add_option("-o,--output", o->output,
                  "output EXR: a frame pattern or one file; folders are created")
      ->required();
  cmd->add_option(
      "--frames", o->frames,
      "frames: N, A-B, A-BxSTEP (every STEP-th), lists such as 1,3,5-8, negative frames "
      "(default: every frame found)");
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
  cmd->add_flag("--skip-existing", o->skip_existing,
                "resume: leave the frames whose files this job already made, complete (same "
                "preset, same inputs); a temporal chain still passes through them, so the frames "
                "made are those an uninterrupted run makes");
  cmd->add_flag("-q,--quiet", o->quiet, "no progress lines and no summary");
  cmd->add_option(
      "--log-json", o->log_json,
      "append a JSON line per event to FILE: the run's start, each frame written "
      "(stage times, camera, cut, history), warnings, and its end with the exit status");
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
}

}  // namespace

void add_run(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd =
      app.add_subcommand("run", "compute the requested layers for every frame of a sequence");
  add_run_options(cmd, o);
  cmd->callback([o] { run(*o); });
}

namespace {

// Run's options parsed from `args` (after INPUT) into a fresh RunOptions; `app` keeps them.
std::shared_ptr<RunOptions> parse_run_args(CLI::App& app, const std::string& input,
                                           const std::vector<std::string>& args,
                                           const std::string& context) {
  auto o = std::make_shared<RunOptions>();
  add_run_options(&app, o);
  std::vector<std::string> reversed{args.rbegin(), args.rend()};
  reversed.push_back(input);
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw Error(Exit::usage, context + ": " + e.what());
  }
  return o;
}

}  // namespace

void run_command(const std::string& input, const std::vector<std::string>& args,
                 const std::string& context) {
  CLI::App app{"run"};
  run(*parse_run_args(app, input, args, context));
}

RunRequest read_run_request(const std::string& input, const std::vector<std::string>& args,
                            const std::string& context) {
  CLI::App app{"run"};
  const std::shared_ptr<RunOptions> o = parse_run_args(app, input, args, context);
  for (const char* option :
       {"--frames", "--preroll", "--cut-frames", "--threads", "--skip-existing", "--log-json"})
    if (app.count(option) > 0)
      throw Error(Exit::usage, context + ": " + option + " is set by the plan, not given to run");
  RunRequest r;
  r.output = {o->output, o->no_display, o->display_out, o->display_layer,
              io::DisplaySettings{o->ocio_config, o->input_space, o->display, o->view}};
  r.params = o->params.load();
  return r;
}

}  // namespace hbil::cli
