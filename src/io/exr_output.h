// exr_output.h: writing hbil's multi-layer EXR frames.
//
// One single-part scanline EXR per frame, compressed as the preset says (compression; RLE,
// the default, by hbil itself: io/exr_rle.h), colour layers as half floats unless
// colour_half is false, data layers 32-bit float, channels named <layer>.<chan> (ao.Y,
// bentcone.X/Y/Z/W). The input's header attributes are copied
// through; hbil adds hbil:version, hbil:preset (the effective parameters as JSON),
// hbil:camera (the camera used, JSON), hbil:job (what the frame was made from, for
// `run --skip-existing`) and the standard worldToCamera / worldToNDC.
// Frames are written to a hidden temporary file in the output folder and renamed into
// place only by commit(), so no reader ever sees a partial frame and a failed run leaves
// what was there before.
#pragma once

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hbil/ao_frame.h"
#include "hbil/camera.h"
#include "hbil/params.h"
#include "io/temporaries.h"

namespace hbil::io {

// One channel of an output file: its name, where its values are (channel of pixel i at
// src[i * stride]; null: the constant 1) and whether it is stored as half.
struct OutputChannel {
  std::string name;
  const float* src;
  size_t stride;
  bool half;
};
// The channels of the requested layers, in the order of Params::outputs.
std::vector<OutputChannel> output_plan(const AoFrame& f, const Params& p);
// Bytes of one pixel of the plan (4 per float channel, 2 per half).
size_t pixel_bytes(const std::vector<OutputChannel>& plan);
// A value that cannot be written: a NaN or an infinity.
struct NonFinite {
  size_t pixel = 0;    // index in the image, y * width + x
  size_t channel = 0;  // in the plan
  float value = 0;
};
// Rows [y0, y1) of the output, each pixel's channels packed in the plan's order and formats.
// A finite value beyond the range of a half channel is stored as the largest half of its
// sign (±65504), not as an infinity. Returns the first non-finite value met (lowest pixel,
// then channel), which is packed as it is: the caller must not write the rows then.
std::optional<NonFinite> output_rows(const std::vector<OutputChannel>& plan, int width, int y0,
                                     int y1, unsigned char* dst);

// The camera as the JSON stored in hbil:camera.
std::string camera_json(const Camera& c);

// Writes the requested layers of `f` to a temporary file beside `final_path` (creating its
// folder) and returns the temporary's path. Throws Error(Exit::output) when the file cannot
// be written. No output holds a NaN or an infinity: every value is checked as it is packed,
// and a non-finite one is an internal error, Error(Exit::failure), naming the frame (when
// `frame` is given), the file, the channel, the pixel and the value; the temporary is
// removed then.
// `job`: the frame's job digest, stored as hbil:job when not empty (pipeline/frame_output.h).
std::string write_temporary(const std::string& final_path, const AoFrame& f,
                            const OIIO::ImageSpec& input_header, const Params& p, const Camera& cam,
                            std::optional<int> frame = std::nullopt, const std::string& job = "");

// Renames a temporary into place (replacing an older file). Throws Error(Exit::output).
void commit(const std::string& temporary, const std::string& final_path);

// Writes `text` to a temporary beside `path` and renames it into place: the file appears
// whole or not at all. Throws Error(Exit::output).
void write_file(const std::string& path, const std::string& text);

// Files waiting as temporaries (add()) until commit() renames them into place: the files of
// one frame (its EXR and display image), or of one command that is all or nothing. discard()
// removes the waiting ones and, when nothing was committed yet, the output folders that were
// missing when expect() was called.
class OutputBatch {
 public:
  // Before anything is written: a file the command will write. Its topmost missing folder
  // is remembered for discard().
  void expect(const std::string& final_path);
  void add(const std::string& temporary, const std::string& final_path);
  // Renames every temporary into place, in order. Throws Error(Exit::output).
  void commit();
  void discard() noexcept;

 private:
  std::vector<std::pair<std::string, std::string>> files_;  // temporary, final
  std::set<std::filesystem::path> created_;
  bool committed_ = false;
};

}  // namespace hbil::io
