// frame_output.h: where a sequence job's frames go as files: the EXR of the requested layers
// per frame and, beside it, a display image through OpenColorIO. Every file is written
// under a hidden temporary name and renamed into place by commit(), when the whole run has
// succeeded; discard() removes them (and the folders the run created) after a failure, so
// that a failed run leaves the output folder as it was.
#pragma once

#include <memory>
#include <optional>
#include <string>

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

  // Writes the frame's files as temporaries (thread-safe; one frame at a time is enough).
  void write(const FrameResult& r);
  void commit() { batch_.commit(); }
  void discard() noexcept { batch_.discard(); }

 private:
  io::FramePattern out_;
  const Params& p_;
  std::optional<io::FramePattern> display_pattern_;
  std::string display_layer_, display_out_;
  std::optional<io::DisplayTransform> display_;
  io::OutputBatch batch_;
};

}  // namespace hbil::pipeline
