// farm.h: a shot cut into chunks for a render farm (`hbil farm`): the plan, the command each
// chunk runs, the Slurm job array that runs them, and the check that every frame is in place.
//
// Chunks follow the shot's cuts: a cut (given with --cut-frames, or found from the camera as
// the temporal chain finds it) starts a chunk, and that chunk needs no pre-roll; between cuts
// the frames are cut into chunks of the plan's size, the last one shorter (with
// history_window, of about that size, where a chunk needs the least pre-roll). Every other chunk
// computes its pre-roll first (never reaching back across a cut), so that its first frame
// carries the history a run over the whole shot gives it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hbil/params.h"
#include "pipeline/frame_output.h"

namespace hbil::pipeline {

struct FarmChunk {
  std::vector<int> frames;  // written by the chunk, ascending
  int preroll = 0;          // its --preroll
  std::string starts;       // why it starts there: "shot", "cut: <reason>", "chunk"
};

struct FarmPlan {
  std::string hbil;              // the version that made the plan
  std::string directory;         // where every chunk runs (relative paths start there)
  std::string shot;              // input frame pattern
  std::vector<std::string> run;  // run's options after INPUT, but for those the plan sets
  std::string cut_frames;        // --cut-frames given to every chunk ("": none)
  std::vector<int> cuts;         // frames that start a new shot, given or found
  int chunk_size = 0;            // frames per chunk
  int preroll = 0;               // frames of pre-roll of a chunk that follows another
  std::string preroll_why;       // how the pre-roll was chosen
  int width = 0, height = 0;     // of the frames
  int memory_mb = 0;             // for each task (Slurm --mem)
  std::vector<FarmChunk> chunks;
};

// What `hbil farm plan` is given.
struct FarmRequest {
  std::string shot, frames, cut_frames;
  std::vector<std::string> run;  // run's options after INPUT
  int chunk_size = 50;
  std::string preroll = "auto";  // "auto" or a count
};

// The pre-roll that keeps a chunk's first frame within kSeamTolerance (relative RMSE of the
// composite) of a whole run's, from the parameters' temporal memory; `why` says how. 0
// without a temporal chain.
inline constexpr double kSeamTolerance = 1e-3;
int seam_preroll(const Params& p, std::string* why = nullptr);
// With history_window: the pre-roll of a chunk that starts at `frame` (frames at the
// sequence's `step`): what its means reach back (window_memory) and kFeedbackSettle frames
// more for the light fed back. 0 without.
inline constexpr int kFeedbackSettle = 3;
int window_preroll(const Params& p, int frame, int step);

// Peak memory of one `hbil run` over frames of width x height, MB: a fit of the measured peaks
// (README "Speed"), with the overlap on up to 2^22 pixels and off above, as run's "auto" does.
int run_memory_mb(int width, int height);

// The plan: frames as plan_sequence takes them, the chunks cut as above. Reads each frame's
// header and, with a temporal chain, its depth and camera to find the cuts. Throws what
// plan_sequence and SequenceJob throw, Error(Exit::usage) for a bad chunk size or pre-roll.
FarmPlan make_farm_plan(const FarmRequest& r, const Params& params);

nlohmann::ordered_json to_json(const FarmPlan& plan);
// Throws Error(Exit::input, "<where>: ...") for a plan that is not one.
FarmPlan farm_plan_from_json(const nlohmann::json& j, const std::string& where);

// The options of chunk `index`'s run after INPUT: the plan's, then --frames, --preroll,
// --cut-frames, --skip-existing (a task run again resumes), and `threads` when > 0 and
// `log_json` when not empty.
std::vector<std::string> chunk_run_args(const FarmPlan& plan, size_t index, int threads,
                                        const std::string& log_json);

// What is missing of a chunk: "" when every frame is in place, complete and made by the
// chunk's own job (FrameOutput::done), else the first frame that is not and why.
struct ChunkState {
  size_t index = 0;
  std::vector<int> missing;  // frames not done
  std::string why;           // about the first of them
};
ChunkState check_chunk(const FarmPlan& plan, size_t index, const Params& params,
                       const OutputSettings& output);

// Slurm: the job array (one task per chunk) and the check that runs after it.
struct SlurmSettings {
  std::string plan_path;            // as the scripts name it (made absolute)
  std::string hbil;                 // the hbil binary the tasks run
  std::string log_dir;              // task logs and run logs
  int cpus = 2;                     // --cpus-per-task, given to run as --threads
  int memory_mb = 0;                // --mem (0: the plan's)
  std::vector<std::string> sbatch;  // more #SBATCH lines, e.g. "--partition=post"
  std::string job_name;             // "" = "hbil-" + the shot's name
};
std::string slurm_array_script(const FarmPlan& plan, const SlurmSettings& s);
std::string slurm_check_script(const FarmPlan& plan, const SlurmSettings& s,
                               const std::string& array_script);

}  // namespace hbil::pipeline
