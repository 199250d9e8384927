// run.cpp: `hbil run INPUT -o OUTPUT`: the per-frame chain over a sequence.
#include <tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <set>

#include "cli/commands.h"
#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "io/exr_frame.h"
#include "io/exr_output.h"
#include "io/sequence.h"

namespace hbil::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RunOptions {
  std::string input, output, frames;
  int threads = 0;
  bool quiet = false, verbose = false;
  ParamOptions params;
};

// The frames to process and their input and output paths.
struct Job {
  std::vector<int> frames;
  io::FramePattern in, out;
};

Job plan(const RunOptions& o) {
  Job job{{}, io::FramePattern(o.input), io::FramePattern(o.output)};
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
  return job;
}

void run(const RunOptions& o) {
  const Params p = o.params.load();
  const Job job = plan(o);
  std::unique_ptr<tbb::global_control> threads;
  if (o.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    o.threads);
  const bool tty = isatty(STDERR_FILENO);

  // Finished frames wait as hidden temporaries and are renamed into place only when every
  // frame succeeded: a failed run leaves the output folder as it was.
  std::vector<std::pair<std::string, std::string>> done;  // temporary, final
  // Output folders this run creates (the topmost missing ancestor of each): removed again
  // when the run fails.
  std::set<fs::path> created;
  for (int f : job.frames) {
    fs::path dir = fs::absolute(fs::path(job.out.path(f))).parent_path(), top;
    for (; !dir.empty() && !fs::exists(dir) && dir != dir.parent_path(); dir = dir.parent_path())
      top = dir;
    if (!top.empty()) created.insert(top);
  }
  auto discard = [&] {
    std::error_code ec;
    for (const auto& d : done) fs::remove(d.first, ec);
    for (const auto& dir : created) fs::remove_all(dir, ec);
  };
  const auto start = Clock::now();
  int width = 0, height = 0;
  std::string first_path;
  try {
    for (size_t k = 0; k < job.frames.size(); ++k) {
      const auto t0 = Clock::now();
      const int frame = job.frames[k];
      const io::InputFrame in = io::open_frame(job.in.path(frame), frame, p);
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
      GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
      const auto t_read = Clock::now();
      const Camera cam = io::find_camera(in, g, p);
      const auto t_camera = Clock::now();
      const AoFrame result = compute_ao_frame(g, cam, p);
      const auto t_compute = Clock::now();
      const std::string out_path = job.out.path(frame);
      done.emplace_back(io::write_temporary(out_path, io::make_output(result, p), in.spec, p, cam),
                        out_path);
      if (o.verbose) {
        auto ms = [](auto a, auto b) {
          return std::chrono::duration<double, std::milli>(b - a).count();
        };
        char line[256];
        std::snprintf(
            line, sizeof line,
            "hbil: frame %d: read %.0f ms, camera %.0f ms, compute %.0f ms, write %.0f ms\n", frame,
            ms(t0, t_read), ms(t_read, t_camera), ms(t_camera, t_compute),
            ms(t_compute, Clock::now()));
        std::cerr << line;
      }
      if (!o.quiet) {
        const double s = std::chrono::duration<double>(Clock::now() - t0).count();
        char line[512];
        std::snprintf(line, sizeof line, "hbil: frame %d (%zu/%zu) %.3f s  camera: %s", frame,
                      k + 1, job.frames.size(), s, cam.source.c_str());
        std::cerr << (tty ? "\r\033[K" : "") << line << (tty ? "" : "\n") << std::flush;
      }
    }
    for (const auto& d : done) io::commit(d.first, d.second);
  } catch (...) {
    if (tty && !o.quiet) std::cerr << "\n";
    discard();
    throw;
  }
  const double total = std::chrono::duration<double>(Clock::now() - start).count();
  if (!o.quiet) {
    char line[256];
    std::snprintf(line, sizeof line, "hbil: %zu frames, %.3f s per frame, %.2f s in all",
                  job.frames.size(), total / double(job.frames.size()), total);
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
  cmd->add_option("--threads", o->threads,
                  "worker threads (0 = all cores); results are identical for any count")
      ->default_val(0)
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("-q,--quiet", o->quiet, "no progress lines and no summary");
  cmd->add_flag(
      "-v,--verbose", o->verbose,
      "also print the time each frame spends reading, finding the camera, computing and writing");
  o->params.add_to(*cmd);
  cmd->callback([o] { run(*o); });
}

}  // namespace hbil::cli
