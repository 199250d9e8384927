// frame_output.h: where a sequence job's frames go as files: the EXR of the requested layers
// per frame and, beside it, a display image through OpenColorIO. Each file is written under
// a hidden temporary name (io/temporaries.h), and a frame's files are renamed into place
// together once both are complete: a failure keeps the frames finished before it and
// leaves the files of the failing frame and of later ones as they were.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/display.h"
#include "io/exr_output.h"
#include "io/sequence.h"
#include "pipeline/sequence_job.h"

namespace hbil::pipeline {

struct OutputSettings {
  std::string output;         // EXR frame pattern or one file
  bool no_display = false;    // write no display image
  std::string display_out;    // display-image pattern; "" = output with .png when shown
  std::string display_layer;  // "" = composite when computed, else the first output
  io::DisplaySettings display;
};

// The config shipped with hbil: installed beside the binary, else in the source tree.
std::string shipped_ocio_config();

class FrameOutput {
 public:
  // Checks the settings against the job before any frame is computed: an output pattern for
  // a sequence, no output over its own input, a display layer that is computed, a display
  // image name that is not the EXR's. Throws Error(Exit::usage), or Error(Exit::input) for
  // a broken OCIO config.
  FrameOutput(const OutputSettings& s, const SequenceJob& job);

  // "" without display images, else "<pattern> (<layer>): <OCIO description>".
  std::string describe_display() const;

  // Removes the temporaries a killed run left in the output folders (io/temporaries.h);
  // returns how many.
  int remove_stale() const;
  // Writes the frame's files and renames them into place (one frame at a time). A failure
  // removes what the frame wrote. `committed` runs once they are in place, before an
  // interrupt that arrived meanwhile takes effect (io::FrameCommit), so that what it records
  // (a log line) is never missing for a frame in place.
  void write(const FrameResult& r, const std::function<void()>& committed = {});
  // The job digest of a planned frame, stored in its EXR as hbil:job: a hash of hbil's
  // version, the effective parameters, the display image's settings, the cuts, the
  // environment file and the inputs (file name, size, modification time) the frame is made
  // from: its own, and with a temporal chain every one from the run's first frame (pre-roll
  // included) to it, since they all shape its history.
  const std::string& job(int frame) const { return jobs_.at(frame); }
  // Whether a frame's files are in place, complete and made by this job (run
  // --skip-existing): its EXR holds this job digest and its first and last rows read, and
  // its display image, when the run makes one, is there and reads. When not, `why` says
  // what is missing or different.
  bool done(int frame, std::string* why = nullptr) const;
  // After a failure: removes the output folders the run created if no frame was written.
  void discard() noexcept { batch_.discard(); }
  // The frames written so far, in order.
  const std::vector<int>& written() const { return written_; }
  // Frame `frame`'s EXR, and its display image ("" without display images).
  std::string path(int frame) const { return out_.path(frame); }
  std::string display_path(int frame) const {
    return display_pattern_ ? display_pattern_->path(frame) : std::string();
  }

 private:
  io::FramePattern out_;
  const Params& p_;
  std::optional<io::FramePattern> display_pattern_;
  std::string display_layer_, display_out_;
  std::optional<io::DisplayTransform> display_;
  io::OutputBatch batch_;
  std::vector<std::string> folders_;  // where the files go
  std::vector<int> written_;
  std::map<int, std::string> jobs_;  // frame -> job digest
};

}  // namespace hbil::pipeline
