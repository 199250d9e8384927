// farm.cpp: see farm.h.
#include "pipeline/farm.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "hbil/error.h"
#include "hbil/reduced.h"
#include "hbil/scene_scale.h"
#include "hbil/temporal.h"
#include "io/exr_frame.h"
#include "io/sequence.h"
#include "pipeline/sequence_job.h"

namespace hbil::pipeline {

namespace fs = std::filesystem;

namespace {

// A word for the shell: single-quoted unless it is plain.
std::string shell_word(const std::string& w) {
  const bool plain = !w.empty() && std::all_of(w.begin(), w.end(), [](unsigned char c) {
    return std::isalnum(c) || std::string_view("-_./=:,+@%").find(char(c)) != std::string::npos;
  });
  if (plain) return w;
  std::string q = "'";
  for (char c : w) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The Slurm job name: as given, else "hbil-" and the shot's folder.
std::string job_name(const FarmPlan& plan, const SlurmSettings& s) {
  if (!s.job_name.empty()) return s.job_name;
  return "hbil-" + fs::path(plan.shot).parent_path().filename().string();
}

}  // namespace

int window_preroll(const Params& p, int frame, int step) {
  if (!p.temporal || p.history_window <= 0) return 0;
  // The radiance cache reads the frames of its last radiance_cache frame numbers.
  const int memory = std::max(window_memory(p.history_window, frame), p.radiance_cache);
  return (memory + std::max(step, 1) - 1) / std::max(step, 1) + kFeedbackSettle;
}

int seam_preroll(const Params& p, std::string* why) {
  if (!p.temporal) {
    if (why) *why = "no temporal chain (temporal false): chunks need no pre-roll";
    return 0;
  }
  if (p.history_window > 0) {
    // A frame's means reach back at most 2W − 2 frames (temporal.h); the irradiance fed back
    // from before the chunk fades by a bounce a frame after that (bench/seam.sh on the two
    // 64-frame moves, W = 6: at most 1.5e-4 at the starts the plan picks, with W − 1 +
    // kFeedbackSettle = 8 frames; 7.8e-5 at the worst start, with 2W − 2 + 3 = 13).
    const int w = p.history_window;
    const int preroll = std::max(2 * w - 2, p.radiance_cache) + kFeedbackSettle;
    if (why) {
      std::ostringstream s;
      s << "history_window " << w << ": a frame's means reach back at most " << 2 * w - 2
        << " frames, and " << kFeedbackSettle << " more let the light fed back settle; "
        << "chunks start within " << w << " frames of every chunk_size where "
        << w - 1 + kFeedbackSettle << " are enough";
      *why = s.str();
    }
    return preroll;
  }
  // A chunk that starts cold differs from a whole run's frame there by kColdDifference of the
  // composite (relative RMSE), and the difference fades by a factor r a frame: the history
  // keeps history_weight of itself, and the light fed back through it (feedback) a fifth of
  // what the accumulation lets go. Fitted on two 64-frame moves (samples/blender study_shots.py
  // and room_shots.py --shot long, README "On the farm"; bench/seam.sh, chunk at frame 41):
  // 0.9 gives r = 0.92, where 0.89 (room) and 0.83 (study) were measured between 16 and 24
  // frames of pre-roll; 0.8 gives 0.84 (measured 0.84 and 0.79 between 8 and 16), 0.7 gives
  // 0.76 (0.79 and 0.75).
  constexpr double kColdDifference = 0.02;
  const double w = std::clamp(p.history_weight, 0.0, 0.99);
  const double r = w + (1 - w) * (p.feedback ? 0.2 : 0.0);
  // At least the radiance cache's frames, which it reads as they were computed.
  const int preroll = std::max(
      p.radiance_cache,
      r > 0 ? std::max(0, int(std::ceil(std::log(kSeamTolerance / kColdDifference) / std::log(r))))
            : 0);
  if (why) {
    std::ostringstream s;
    s.precision(3);
    s << "a cold start's difference of " << kColdDifference << " fades by " << r
      << " a frame (history_weight " << p.history_weight << (p.feedback ? ", feedback" : "")
      << ") to " << kSeamTolerance << " in " << preroll << " frames (history_window 6 would need "
      << 6 - 1 + kFeedbackSettle << ": man hbil)";
    *why = s.str();
  }
  return preroll;
}

int run_memory_mb(int width, int height) {
  // Peak RSS with the default outputs and a PNG (bench/speed.sh on room_poles, 2026-12-07):
  // 155 MB at 256x144, 839 MB at 1920x1080 (overlap on: three frames in flight), 1098 MB at
  // 3840x2160 (overlap off). farm slurm adds a quarter for other shots (more passes, a
  // panorama).
  const double mpx = double(width) * double(height) / 1e6;
  const bool overlap = double(width) * double(height) <= double(1 << 22);
  return int(std::ceil(143 + (overlap ? 336 : 115) * mpx));
}

FarmPlan make_farm_plan(const FarmRequest& r, const Params& requested) {
  if (r.chunk_size < 1)
    throw Error(Exit::usage, "--chunk " + std::to_string(r.chunk_size) + ": must be 1 or more");
  FarmPlan plan;
  plan.hbil = HBIL_VERSION;
  plan.directory = fs::current_path().string();
  plan.shot = r.shot;
  plan.run = r.run;
  plan.cut_frames = r.cut_frames;
  plan.chunk_size = r.chunk_size;
  const SequencePlan seq = plan_sequence(r.shot, r.frames, 0, r.cut_frames);
  if (!seq.input.is_sequence())
    throw Error(Exit::usage, r.shot + ": a farm plan needs a frame pattern, not one file");
  // Every header, the passes and the sizes, as a run checks them before its first frame.
  const SequenceJob job(seq, requested);
  const Params& p = job.params();
  plan.width = job.first().spec.width;
  plan.height = job.first().spec.height;
  plan.memory_mb = run_memory_mb(plan.width, plan.height);
  // history_window keeps 12 more floats of history a searched pixel (1 in f x f with
  // search_scale f), twice while it is reprojected.
  if (p.temporal && p.history_window > 0) {
    const int f = effective_search_scale(p, plan.width, plan.height);
    const double texels =
        double(reduced_extent(plan.width, f)) * double(reduced_extent(plan.height, f));
    plan.memory_mb += int(std::ceil(2.0 * 12 * 4 * texels / 1e6));
  }
  if (r.preroll == "auto") {
    plan.preroll = seam_preroll(p, &plan.preroll_why);
  } else {
    try {
      size_t used = 0;
      plan.preroll = std::stoi(r.preroll, &used);
      if (used != r.preroll.size() || plan.preroll < 0) throw std::invalid_argument(r.preroll);
    } catch (const std::exception&) {
      throw Error(Exit::usage, "--preroll " + r.preroll + ": expected auto or a count of frames");
    }
    plan.preroll_why = "given";
  }
  // Cuts: given, then found from the cameras (the chain's camera test; a cut it finds only
  // from rejected history is not known before the frames are computed).
  std::vector<std::pair<int, std::string>> cuts;
  for (int c : seq.cuts) cuts.emplace_back(c, "given");
  // A frame whose predecessor at the sequence's step is missing starts without history too.
  const int step = sequence_step(seq.frames);
  if (p.temporal) {
    Camera prev;
    for (size_t k = 0; k < seq.frames.size(); ++k) {
      const int f = seq.frames[k];
      const io::InputFrame in = io::open_frame(seq.input.path(f), f, p);
      GBuffer g = io::read_fields(in, {in.has("depth") ? "depth" : "position"}, p);
      const Camera cam = io::find_camera(in, g, p);
      if (k > 0 && !seq.cuts.count(f)) {
        std::string why = seq.frames[k] - seq.frames[k - 1] > step
                              ? "frame " + std::to_string(seq.frames[k - 1] + step) + " missing"
                              : camera_cut(prev, cam, measure_scene(g, cam, p).depth_median, p);
        if (!why.empty()) cuts.emplace_back(f, why);
      }
      prev = cam;
    }
  }
  std::sort(cuts.begin(), cuts.end());
  for (const auto& c : cuts) plan.cuts.push_back(c.first);
  // Chunks: a new one at the shot's start, at each cut, and every chunk_size frames between.
  // With history_window and an automatic pre-roll, within W frames of that, at the frame
  // whose means reach back least (one chain restarting there: W − 1 frames), each chunk with
  // its own pre-roll.
  const int window = r.preroll == "auto" && p.temporal ? p.history_window : 0;
  auto boundary = [&](size_t since_start, int f) {
    const size_t n = size_t(r.chunk_size);
    if (window == 0) return since_start == n;
    const int m = 2 * window;
    const bool least = ((f + 1) % m + m) % m == 0;
    return (least && since_start + size_t(window) >= n) || since_start + 1 >= n + size_t(window);
  };
  size_t since_start = 0;
  for (size_t k = 0; k < seq.frames.size(); ++k) {
    const int f = seq.frames[k];
    const auto cut = std::find_if(cuts.begin(), cuts.end(), [&](auto& c) { return c.first == f; });
    const bool at_cut = cut != cuts.end() && k > 0;
    if (k == 0 || at_cut || boundary(since_start, f)) {
      FarmChunk c;
      c.starts = k == 0 ? "shot" : at_cut ? "cut: " + cut->second : "chunk";
      if (!at_cut && k > 0) {
        // Pre-roll back to, never across, the last cut before the chunk.
        int floor = seq.frames.front();
        for (const auto& cc : cuts)
          if (cc.first <= f) floor = std::max(floor, cc.first);
        const int want = window > 0 ? window_preroll(p, f, step) : plan.preroll;
        c.preroll = std::min(want, f - floor);
      }
      plan.chunks.push_back(c);
      since_start = 0;
    }
    plan.chunks.back().frames.push_back(f);
    ++since_start;
  }
  return plan;
}

nlohmann::ordered_json to_json(const FarmPlan& plan) {
  nlohmann::ordered_json j;
  j["hbil"] = plan.hbil;
  j["directory"] = plan.directory;
  j["shot"] = plan.shot;
  j["run"] = plan.run;
  j["cut_frames"] = plan.cut_frames;
  j["cuts"] = plan.cuts;
  j["chunk_size"] = plan.chunk_size;
  j["preroll"] = plan.preroll;
  j["preroll_why"] = plan.preroll_why;
  j["resolution"] = {plan.width, plan.height};
  j["memory_mb"] = plan.memory_mb;
  auto& chunks = j["chunks"] = nlohmann::ordered_json::array();
  for (const FarmChunk& c : plan.chunks)
    chunks.push_back({{"frames", io::format_frame_list(c.frames)},
                      {"first", c.frames.front()},
                      {"last", c.frames.back()},
                      {"count", c.frames.size()},
                      {"preroll", c.preroll},
                      {"starts", c.starts}});
  return j;
}

FarmPlan farm_plan_from_json(const nlohmann::json& j, const std::string& where) {
  FarmPlan plan;
  try {
    plan.hbil = j.at("hbil").get<std::string>();
    plan.directory = j.at("directory").get<std::string>();
    plan.shot = j.at("shot").get<std::string>();
    plan.run = j.at("run").get<std::vector<std::string>>();
    plan.cut_frames = j.at("cut_frames").get<std::string>();
    plan.cuts = j.at("cuts").get<std::vector<int>>();
    plan.chunk_size = j.at("chunk_size").get<int>();
    plan.preroll = j.at("preroll").get<int>();
    plan.preroll_why = j.value("preroll_why", "");
    plan.width = j.at("resolution").at(0).get<int>();
    plan.height = j.at("resolution").at(1).get<int>();
    plan.memory_mb = j.at("memory_mb").get<int>();
    for (const auto& c : j.at("chunks")) {
      FarmChunk chunk;
      chunk.frames = io::parse_frame_list(c.at("frames").get<std::string>(), "chunk frames");
      chunk.preroll = c.at("preroll").get<int>();
      chunk.starts = c.value("starts", "");
      if (chunk.preroll < 0 || chunk.preroll > io::kMaxFrames)
        throw std::invalid_argument("a chunk's pre-roll is not 0 to " +
                                    std::to_string(io::kMaxFrames));
      plan.chunks.push_back(std::move(chunk));
    }
  } catch (const Error& e) {
    throw Error(Exit::input, where + ": not a farm plan (" + e.what() + ")");
  } catch (const std::exception& e) {
    throw Error(Exit::input, where + ": not a farm plan (" + e.what() + ")");
  }
  if (plan.chunks.empty()) throw Error(Exit::input, where + ": not a farm plan (no chunks)");
  if (plan.memory_mb < 0 || plan.memory_mb > (1 << 24))
    throw Error(Exit::input,
                where + ": not a farm plan (memory_mb " + std::to_string(plan.memory_mb) + ")");
  return plan;
}

std::vector<std::string> chunk_run_args(const FarmPlan& plan, size_t index, int threads,
                                        const std::string& log_json) {
  const FarmChunk& c = plan.chunks.at(index);
  std::vector<std::string> a = plan.run;
  a.insert(a.end(), {"--frames", io::format_frame_list(c.frames), "--preroll",
                     std::to_string(c.preroll), "--skip-existing"});
  if (!plan.cut_frames.empty()) a.insert(a.end(), {"--cut-frames", plan.cut_frames});
  if (threads > 0) a.insert(a.end(), {"--threads", std::to_string(threads)});
  if (!log_json.empty()) a.insert(a.end(), {"--log-json", log_json});
  return a;
}

ChunkState check_chunk(const FarmPlan& plan, size_t index, const Params& params,
                       const OutputSettings& output) {
  ChunkState st;
  st.index = index;
  const FarmChunk& c = plan.chunks.at(index);
  try {
    const SequencePlan seq =
        plan_sequence(plan.shot, io::format_frame_list(c.frames), c.preroll, plan.cut_frames);
    const SequenceJob job(seq, params);
    const FrameOutput out(output, job);
    for (int f : c.frames) {
      std::string why;
      if (!out.done(f, &why)) {
        if (st.missing.empty()) st.why = why;
        st.missing.push_back(f);
      }
    }
  } catch (const Error& e) {
    // An input that went missing or bad since the plan: no frame of the chunk can be told
    // done, since none can be remade.
    st.missing = c.frames;
    st.why = e.what();
  }
  return st;
}

std::string slurm_array_script(const FarmPlan& plan, const SlurmSettings& s) {
  const std::string name = job_name(plan, s);
  // The plan's estimate with a quarter more, at least 512 MB: Slurm ends a task that passes
  // its --mem.
  const int memory =
      s.memory_mb > 0 ? s.memory_mb : std::max(512, int(std::ceil(plan.memory_mb * 1.25)));
  std::ostringstream o;
  o << "#!/bin/bash\n"
    << "# hbil farm slurm: " << plan.chunks.size() << " chunks of " << plan.shot
    << ", one array task each (plan " << s.plan_path << ").\n"
    << "#   sbatch THIS_FILE                 runs every chunk\n"
    << "#   sbatch --array=3,7 THIS_FILE     runs chunks 3 and 7 again (hbil farm check names "
       "them)\n"
    << "# A task run again resumes: its frames already in place are not made again.\n"
    << "#SBATCH --job-name=" << name << "\n"
    << "#SBATCH --array=0-" << plan.chunks.size() - 1 << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=" << s.cpus << "\n"
    << "#SBATCH --mem=" << memory << "M\n"
    << "#SBATCH --chdir=" << plan.directory << "\n"
    << "#SBATCH --output=" << s.log_dir << "/" << name << "-%A_%a.out\n";
  for (const std::string& extra : s.sbatch) o << "#SBATCH " << extra << "\n";
  o << "set -euo pipefail\n"
    << "task=${SLURM_ARRAY_TASK_ID:?submit this script with sbatch}\n"
    << "exec " << shell_word(s.hbil) << " farm run " << shell_word(s.plan_path)
    << " --chunk \"$task\" --threads \"${SLURM_CPUS_PER_TASK:-" << s.cpus << "}\" --log-json "
    << shell_word(s.log_dir) << "/chunk-\"$task\".jsonl\n";
  return o.str();
}

std::string slurm_check_script(const FarmPlan& plan, const SlurmSettings& s,
                               const std::string& array_script) {
  const std::string name = job_name(plan, s) + "-check";
  std::ostringstream o;
  o << "#!/bin/bash\n"
    << "# hbil farm slurm: after the job array, checks that every frame of the plan is in\n"
    << "# place and complete; when not, its log names the chunks to submit again.\n"
    << "#   sbatch --dependency=afterany:ARRAY_JOB_ID THIS_FILE\n"
    << "#SBATCH --job-name=" << name << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=1\n"
    << "#SBATCH --mem=" << std::max(256, plan.memory_mb / 4) << "M\n"
    << "#SBATCH --chdir=" << plan.directory << "\n"
    << "#SBATCH --output=" << s.log_dir << "/" << name << "-%j.out\n";
  for (const std::string& extra : s.sbatch) o << "#SBATCH " << extra << "\n";
  o << "exec " << shell_word(s.hbil) << " farm check " << shell_word(s.plan_path) << " --sbatch "
    << shell_word(array_script) << "\n";
  return o.str();
}

}  // namespace hbil::pipeline
