// calibration.h: the level of the unseen fill (Params::unseen_scale), solved from renders
// with global illumination of some of the shot's frames (Params::calibration).
//
// What the frame does not show lights it through unseen_radiance, whose level no G-buffer
// tells. A render with global illumination tells its mean, even at one sample per pixel and at
// a fraction of the shot's resolution: the mean over its pixels of DiffCol x DiffInd (every
// channel summed). At each calibration frame c, hbil computes frame c alone (no history, as
// with temporal false) with the fill off and on, and the factor s_c is the one whose
// indirect light has the render's mean, over each image's display window (background adds 0
// to both; an overscan's guard band lights the frame but is not the frame a render of it
// stands for). hbil computes on the pixel at the centre of every 2n x 2n block where the run
// searches one pixel in n x n (subsample below): a mean needs fewer pixels than an image.
//
//   s_c = (mean_ref − mean_hbil(s = 0)) / (mean_hbil(s = 1) − mean_hbil(s = 0))
//
// exact for one bounce, where the fill enters the gather linearly; with more bounces
// (Params::bounces) the secant is taken again until the means agree within 0.1 %, at most
// kMaxSolves solves.
//
// With the temporal chain and its feedback (Params::temporal, Params::feedback), each frame the
// run computes after the first is fed the indirect light of the frames before it. A solve then
// computes frame c twice, the second time fed the first's indirect light, so that s_c brings
// the chain's frames to the render's mean once they have a history (the first frame, with
// none, stays below it). SequenceJob turns that off for a run of one frame, which has none. Still
// linear in s for one bounce. s_c is clamped to [0, kMaxScale]; where the fill reaches no pixel
// (nothing of the frame escapes, or unseen_radiance is 0) it is 1.
//
// Frame f uses s interpolated linearly in the frame number between the calibration frames
// around it, and the nearest one's outside them. Each s_c depends on frame c alone, so a farm
// chunk uses the factors the whole run uses.
//
// Params::calibration_tiles splits each calibration frame into a grid of tiles (at most one per
// 256 pixels of the render, and per 64 of the pixels computed) and solves each tile's factor
// the same way from the same two searches, on the tile's means:
//
//   s_t = (ref_t − hbil_t(s = 0)) / (hbil_t(s = 1) − hbil_t(s = 0)),   r_t = s_t / s_c
//
// clamped to [kMinTile, kMaxTile]; r_t = 1 where the fill brings the tile less than
// kTileReach of what it brings the frame (its error is not the fill's). A surface then takes
// s x r at its position (hbil/fill_tiles.h): the render's light where it is, not only its mean.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "hbil/camera.h"
#include "hbil/fill_tiles.h"
#include "hbil/gbuffer.h"
#include "hbil/params.h"
#include "io/sequence.h"

namespace hbil::pipeline {

constexpr double kMaxScale = 64.0;
constexpr int kMaxSolves = 6;
constexpr double kMinTile = 0.25, kMaxTile = 4.0, kTileReach = 0.1;

struct CalibrationPoint {
  int frame = 0;
  std::string path;              // the calibration render
  double reference = 0;          // its mean DiffCol x DiffInd (R + G + B)
  double without = 0, with = 0;  // hbil's mean indirect (R + G + B) with s = 0 and s = 1
  double scale = 1;              // s_c
  // Params::calibration_tiles: the tiles' factors relative to s_c (FillTiles::View, its
  // weight unset); no tiles (cols 0) where the fill reaches no pixel or tiles are off.
  FillTiles::View tiles;
  int solves = 0;       // values of s tried to find it (each one or two searches)
  bool reaches = true;  // false: the fill reaches no pixel (s_c = 1)
  double seconds = 0;
};

// Params::calibration "auto": the input's own file names in a folder "calibration" beside
// its frames ("shot/frame_####.exr" -> "shot/calibration/frame_####.exr"; a single file
// likewise) where at least one of them exists, else "" (no calibration). Anything else is
// returned as given.
std::string resolve_calibration(const std::string& calibration, const io::FramePattern& input);

class Calibration {
 public:
  Calibration() = default;
  // The calibration frames that bear on `frames` (the run's, pre-roll included): for each,
  // the nearest calibration frame at or before it and the nearest at or after it, among the
  // files `p.calibration` finds (a single file: the frame its name numbers, else the shot's
  // first frame on disk). Opens each one's header and finds DiffCol and DiffInd, so that a
  // missing file is Error(Exit::input) and a missing pass Error(Exit::missing_pass), both
  // naming the file, before anything is computed. Nothing is solved yet.
  Calibration(const Params& p, const io::FramePattern& input, const std::vector<int>& frames);

  bool empty() const { return frames_.empty(); }
  const std::vector<int>& frames() const { return frames_; }
  const std::vector<std::string>& paths() const { return paths_; }  // frames()' files

  // The calibration frames frame f takes its factor from: the nearest at or before it and
  // the nearest at or after it (one where they are the same, or one is missing).
  std::vector<int> around(int frame) const;

  // Solves calibration frame c (one of frames()), from `g` and `cam`, its frame as the run
  // read it (colour fields packed or not), or reading frame c of `input`: `p` as the run resolved
  // it. Both give the same point.
  CalibrationPoint solve(const Params& p, const GBuffer& g, const Camera& cam, int c) const;
  CalibrationPoint solve(const Params& p, const io::FramePattern& input, int c) const;
  // Every calibration frame, read from `input`.
  std::vector<CalibrationPoint> solve(const Params& p, const io::FramePattern& input) const;

  // The factor of frame f from solved points (ascending frames), as above.
  static double scale_at(const std::vector<CalibrationPoint>& points, int frame);
  // The tiles of frame f from the same points: each point's with the weight scale_at gives it.
  static FillTiles tiles_at(const std::vector<CalibrationPoint>& points, int frame);

 private:
  std::string pattern_;
  std::vector<int> frames_;
  std::vector<std::string> paths_;
  const std::string& path(int c) const;
};

// The pixel at the centre of every m x m block of g (its colour unpacked), and the camera that
// sees them: what the calibration computes on. m <= 1: g itself, unpacked.
std::pair<GBuffer, Camera> subsample(const GBuffer& g, const Camera& cam, int m);

// The mean over an image's display window (the pixels of its data window inside it) of
// DiffCol x DiffInd, R + G + B (non-finite values count as 0). Throws
// Error(Exit::missing_pass) naming the file for a missing pass.
double reference_indirect_mean(const std::string& path);
// The same, and per tile of a grid over the display window (a pixel belongs to the tile its
// centre lies in), row-major: the mean, the number of pixels and the standard error of the mean
// from the render's noise (its variance per pixel estimated from the differences of horizontal
// neighbours, over the number of pixels), in one reading. `grid` chooses cols x rows from the
// number of pixels the render has in its display window ({0, 0}: no tiles).
struct ReferenceIndirect {
  double mean = 0;
  int cols = 0, rows = 0;
  std::vector<double> tiles, se;
  std::vector<size_t> counts;
};
ReferenceIndirect reference_indirect(const std::string& path,
                                     const std::function<std::pair<int, int>(double)>& grid);

}  // namespace hbil::pipeline
