// sequence.h: frame-numbered file names (input G-buffer sequences and outputs).
//
// Pattern syntax (the frame field must be in the file name, not in a directory):
//   "dir/frame_####.exr"  N '#' = frame number zero-padded to N digits (Blender, oiiotool);
//   "dir/frame_%04d.exr"  printf style, also "%d" (no padding); "%%" is a literal '%';
//   "dir/shot.exr"        no field: a single file.
// A path is formatted like printf("%0*d", N, frame) ("%d": N = 0), so a frame that needs
// more digits than N gets them (frame 10000 with "####" -> "10000", as Blender writes),
// and a negative frame gets a leading '-' ("-001").
// A file on disk belongs to the sequence exactly when path(frame) reproduces its name, so
// "frame_007.exr" is not frame 7 of "frame_%d.exr" and "frame_12.exr" is not a frame of
// "frame_####.exr".
// Errors: malformed patterns and ranges throw hbil::Error(Exit::usage, ...).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace hbil::io {

class FramePattern {
 public:
  // Throws Error(Exit::usage) for two frame fields, "%s" or another conversion than
  // "%d" / "%0Nd", a lone '%', or a frame field in a directory name.
  explicit FramePattern(std::string pattern);

  bool is_sequence() const { return is_sequence_; }
  const std::string& text() const { return text_; }
  // Zero-pad width: the number of '#' or N of "%0Nd"; 0 for "%d" and single files.
  int pad() const { return pad_; }
  // The file of a frame; a single file returns itself whatever the frame.
  std::string path(int frame) const;
  // Frames of the sequence present in the directory (regular files or links to them),
  // ascending. Non-negative frames only. A single file: { frame_number_from_name(file)
  // or 0 } when it exists. Empty when the directory does not exist.
  std::vector<int> existing_frames() const;

 private:
  std::string text_;
  bool is_sequence_ = false;
  std::string prefix_, suffix_;  // path(frame) = prefix_ + digits + suffix_
  int pad_ = 0;
};

// Inclusive frame range for --frames.
struct FrameRange {
  int first = 0;
  int last = 0;
};

// "12" -> {12, 12}; "1-8" -> {1, 8}. Non-negative integers, first <= last, no spaces.
// Throws Error(Exit::usage, "--frames: ...").
FrameRange parse_frame_range(const std::string& text);

// Frame number of a single file from the last digit group of its file name without the
// extension: "dir/shot_0042.exr" -> 42, "a.0007.exr" -> 7; nullopt when the name has no
// digits or the group does not fit in an int.
std::optional<int> frame_number_from_name(const std::string& path);

}  // namespace hbil::io
