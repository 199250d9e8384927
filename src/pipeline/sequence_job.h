// sequence_job.h: one run over a sequence, the loop that `hbil run` and `hbil bench` drive.
// Frames are planned (the frames to deliver, the pre-roll before them, the cuts), then each
// is read, its camera found, computed (through the temporal chain when the preset has one)
// and handed to a sink, with the time each stage took.
//
// With the overlap, frame k+1 is read and frame k−1 delivered while frame k computes (three
// frames in memory); without it each frame is read, computed and delivered in turn (one
// frame in memory). Each stage keeps the frame order, so the results are the same either
// way and for any thread count.
#pragma once

#include <chrono>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "hbil/ao_frame.h"
#include "hbil/params.h"
#include "hbil/scene_scale.h"
#include "hbil/temporal.h"
#include "io/exr_frame.h"
#include "io/sequence.h"
#include "pipeline/calibration.h"

namespace hbil::pipeline {

// Frame `frame` of Params::panorama (the file `path`): the fields RadianceCache::set_panorama
// reads, with the same pass names as the frames (Exit::missing_pass naming the file and the
// channels looked for when one is absent).
GBuffer read_panorama(const std::string& path, int frame, const Params& p);

struct SequencePlan {
  io::FramePattern input{""};
  std::vector<int> frames;   // delivered, in order
  std::vector<int> preroll;  // computed before them, not delivered
  std::set<int> cuts;        // frames that start a new shot (history dropped)
};

// "12,40" -> {12, 40}; any frame list (io::parse_frame_list). Throws
// Error(Exit::usage, "--cut-frames: ...").
std::set<int> parse_cut_frames(const std::string& text);

// The frames of `input` (a pattern or one file): `frames` a frame list (io::parse_frame_list:
// "1-8", "1-100x2", "1,3,5-8"), or every frame found when empty; `preroll` P: the frames that exist
// in [first − P, first − 1]; `cut_frames` as parse_cut_frames. Throws Error(Exit::usage) for
// options that do not fit the input and Error(Exit::input) for a pattern that matches nothing.
SequencePlan plan_sequence(const std::string& input, const std::string& frames, int preroll,
                           const std::string& cut_frames);

struct FrameTimes {
  double read_ms = 0, camera_ms = 0, compute_ms = 0, deliver_ms = 0;
};

// A computed frame, as the sink gets it.
struct FrameResult {
  int frame = 0;
  size_t index = 0;  // 1-based among the delivered frames
  const io::InputFrame* input = nullptr;
  Camera camera;
  AoFrame outputs;
  TemporalReport report;
  bool temporal = false;                          // computed by the temporal chain
  FrameTimes times;                               // deliver_ms is filled after the sink returns
  std::chrono::steady_clock::time_point started;  // when its computation began
};

enum class Overlap { on, off, automatic };

// glibc's heap thresholds for frames of width x height (0 x 0: before the size is known):
// `hbil run` and `hbil bench` call it, so that bench times what run does.
void configure_heap(int width, int height);

// "on", "off", "auto".
Overlap parse_overlap(const std::string& text);

class SequenceJob {
 public:
  // Opens the first frame and resolves outputs "auto" on its header: every frame then
  // computes the same layers, and a later frame that lacks a pass is an error. Opens the
  // header of every other planned frame too, so that a missing or unreadable input is
  // Error(Exit::input) before any frame is computed.
  // Loads the environment (far field) the parameters name, once.
  SequenceJob(SequencePlan plan, const Params& requested);

  const SequencePlan& plan() const { return plan_; }
  const Params& params() const { return p_; }
  const io::InputFrame& first() const { return first_; }
  // The calibration frames the run solves (empty without Params::calibration, or where the
  // outputs gather no light).
  const Calibration& calibration() const { return calibration_; }
  // The missing-pass message of the first "auto" output left out ("" when none was).
  const std::string& why_dropped() const { return why_dropped_; }
  // What gather_radius and thickness "auto" became, and from what ("" when neither was).
  const std::string& scene_description() const { return why_scene_; }
  const SceneScale& scene() const { return scene_; }
  // Whether run() overlaps: "auto" does up to 2^22 pixels (2560x1440).
  bool overlaps(Overlap o) const;

  struct Hooks {
    // Each delivered frame, in order, on a thread of its own (with the overlap, beside the
    // next frame's computation). May throw: the run stops and the exception is passed on.
    std::function<void(FrameResult&)> deliver;
    // After each delivery, on the calling thread, in order.
    std::function<void(const FrameResult&)> delivered;
    // A cut, on the calling thread.
    std::function<void(int frame, const TemporalReport&)> cut;
    // A pre-roll frame computed: its number, k of n, seconds.
    std::function<void(int frame, size_t k, size_t n, double seconds)> preroll_done;
    // Something about a frame's input worth a word that does not stop the run (pixels with
    // a zero-length normal, taken as background), on the calling thread, before the frame
    // is computed. The message names the frame, the file and the first pixel concerned.
    std::function<void(int frame, const std::string& message)> warning;
    // A frame that is done (run's `done`) computed again for the history of the frames
    // after it: its number and seconds.
    std::function<void(int frame, double seconds)> history_only;
    // Each calibration frame solved (Params::calibration), before the first frame is
    // computed, on the calling thread.
    std::function<void(const CalibrationPoint&)> calibrated;
  };
  // With Params::calibration, the calibration frames that bear on the planned frames are
  // solved first (calibration.h), and each frame's fill is scaled by its factor.
  // With a temporal chain, a gap in the frame numbers drops the history: a frame whose
  // predecessor at the sequence's step (the smallest difference between its frame numbers)
  // is missing is computed as after a cut, with the reason "frame N missing".
  // `environment`: the far field's SH, instead of the one the parameters name.
  // `done`: planned frames whose outputs are already in place (run --skip-existing), not
  // delivered again. Without a temporal chain they are not read at all. With one, those
  // before the last frame not done are computed as pre-roll is (not delivered), so that the
  // frames after them get the history an uninterrupted run gives them; those after it are
  // not computed.
  void run(const Hooks& hooks, Overlap overlap = Overlap::automatic,
           const SH9* environment = nullptr, const std::set<int>& done = {}) const;

 private:
  // Whether the run has a temporal chain: decided on the whole plan, pre-roll and done frames
  // included, so that a resumed run computes what an uninterrupted one does.
  bool chained() const { return p_.temporal && plan_.preroll.size() + plan_.frames.size() > 1; }

  SequencePlan plan_;
  io::InputFrame first_;
  Params p_;
  std::string why_dropped_, why_scene_;
  SceneScale scene_;
  std::optional<SH9> environment_;
  Calibration calibration_;
  // Params::radiance_cache_ahead: the frames on disk a run reads ahead, from its first frame's
  // next to radiance_cache_ahead after its last (beyond the plan too: a chunk reads what the
  // whole run reads).
  std::vector<int> ahead_;
};

// The step of a sequence's frames, ascending: the smallest difference between consecutive
// frame numbers (frames rendered on twos: 2), 0 for fewer than two frames. With a temporal
// chain, a frame whose predecessor at this step is missing starts without history.
int sequence_step(const std::vector<int>& frames);

}  // namespace hbil::pipeline
