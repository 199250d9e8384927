// sequence.h: frame-numbered file names (input G-buffer sequences and outputs).
//
// Pattern syntax (the frame field must be in the file name, not in a directory):
//   "dir/frame_####.exr"  N '#' = frame number zero-padded to N digits (Blender's rule; a
//                         lone '#' is one digit, where oiiotool reads four);
//   "dir/frame_@@@@.exr"  N '@' = N digits (oiiotool's rule, the same as Blender's '#');
//   "dir/frame_%04d.exr"  printf style, also "%d" (no padding); "%%" is a literal '%';
//   "dir/shot.exr"        no field: a single file.
// A path is formatted like printf("%0*d", N, frame) ("%d": N = 0), so a frame that needs
// more digits than N gets them (frame 10000 with "####" -> "10000", as Blender writes),
// and a negative frame gets a leading '-' ("-001").
// A file on disk belongs to the sequence exactly when path(frame) reproduces its name, so
// "frame_007.exr" is not frame 7 of "frame_%d.exr" and "frame_12.exr" is not a frame of
// "frame_####.exr".
// Frame lists (--frames, --cut-frames) take oiiotool's syntax, through OpenImageIO's
// Filesystem::enumerate_sequence: "12", "1-100", "1-100x2" (every second), "1-100y2" (the
// others), "1,3,5-8", negative frames ("-5--1", "-3-3"), ranges in either direction.
// Errors: malformed patterns and lists throw hbil::Error(Exit::usage, ...).
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
  // ascending, negative ones included ("frame_-001.exr" is frame -1 of "frame_####.exr"). A single
  // file: { frame_number_from_name(file) or 0 } when it exists. Empty when the directory does not
  // exist.
  std::vector<int> existing_frames() const;

 private:
  std::string text_;
  bool is_sequence_ = false;
  std::string prefix_, suffix_;  // path(frame) = prefix_ + digits + suffix_
  int pad_ = 0;
};

// A frame list in oiiotool's syntax (above) -> its frames, ascending, each once: "1-8x2,3"
// -> {1, 3, 5, 7}. Items are comma-separated, without spaces; a step is a positive number; a
// list holds at most kMaxFrames frames, each within +-kMaxFrame. Throws Error(Exit::usage,
// "<option>: \"<text>\": ...").
constexpr int kMaxFrames = 1000000;
constexpr int kMaxFrame = 999999999;
std::vector<int> parse_frame_list(const std::string& text, const std::string& option = "--frames");
// The inverse: ascending frames -> the shortest list of ranges and steps that parse_frame_list
// reads back as them: {1, 2, 3, 5} -> "1-3,5", {1, 3, 5, 7} -> "1-7x2".
std::string format_frame_list(const std::vector<int>& frames);

// Frame number of a single file from the last digit group of its file name without the
// extension: "dir/shot_0042.exr" -> 42, "a.0007.exr" -> 7; nullopt when the name has no
// digits or the group does not fit in an int.
std::optional<int> frame_number_from_name(const std::string& path);

}  // namespace hbil::io
