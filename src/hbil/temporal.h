// temporal.h: the temporal chain of HBIL over the frames of a sequence.
//
//   frame N: view-space G-buffer -> cut detection -> reprojection of frame N−1's history
//   (reproject.h: scatter with both cameras, or gather through the Vector pass) -> push/pull
//   fill of its disocclusions (pushpull.h) -> horizon search with the slices turned by the
//   frame number and, as source radiance, DiffCol × (DiffDir + reprojected indirect) (+ Emit, see
//   source_radiance) (HBIL §2.3.1 eq. 17: one more bounce every frame) -> accumulation of
//   irradiance, ao and the bent vector with the reprojected history -> outputs; the accumulated
//   result is the history of frame N+1.
//
// Only one frame of history is resident, whatever the length of the sequence.
//
// With a reduced search (search_scale f > 1, reduced.h) the chain works on the searched
// texels: the history holds one texel per f x f block, is reprojected onto the frame's texels
// (a Vector pass's motion taken at each texel's own pixel, divided by f), filled and blended
// there, and the blend is upsampled to every pixel once; the fed-back irradiance is upsampled
// before it meets each pixel's DiffCol. The texels hold the light that reaches them: each
// pixel's diffuse weight (diffuse_weight) is applied to it after the upsample.
//
// Accumulation: a pixel whose history was accepted (depth within history_depth_tolerance,
// normal within history_normal_cos) has n = min(n_prev + 1, history_max) frames and blends
// x = lerp(x_history, x_current, max(1/n, 1 − history_weight)): a plain mean until the history
// is long enough, then an exponential blend. A pixel without history starts at n = 1 with the
// current frame, so newly revealed pixels converge as fast as the first frame did.
//
// With history_window W >= 2 the memory is finite instead: two chains, each a plain mean of
// the frames since it last restarted, restart every 2W frame numbers, W apart, and the output
// blends them with weights that vanish at each chain's first and last frame (temporal.cpp,
// window_weight), so a frame's ao, vis and bent vector depend on at most the 2W − 2 frames
// before it (window_memory), and a farm chunk with that much pre-roll computes them as the
// whole run does, to the bit. The fed-back irradiance is then the previous frame's own,
// before accumulation: it forgets a cut-off past by a bounce per frame, not through the means.
//
// Cuts: given by the caller (--cut-frames), or found: the camera moved farther than
// cut_camera_jump × the frame's median depth or turned more than cut_camera_angle, or the
// history was rejected on more than cut_rejected of the geometry pixels. A cut drops the
// history: the frame is computed as a first frame.
#pragma once

#include <string>
#include <vector>

#include "hbil/ao_frame.h"
#include "hbil/camera.h"
#include "hbil/farfield.h"
#include "hbil/gbuffer.h"
#include "hbil/params.h"
#include "hbil/radiance_cache.h"

namespace hbil {

// What happened to one frame, for the log.
struct TemporalReport {
  bool cut = false;
  std::string cut_reason;    // "given", or what was detected; "" when no cut
  bool first = false;        // no history before this frame (first frame of the run)
  std::string reprojection;  // "scatter" or "vector" ("" without history)
  double history = 0;        // fraction of geometry pixels (texels) with accepted history
  double filled = 0;         // fraction filled by push/pull (feedback only)
};

// The camera test of cut detection: "" when `cur` can follow `prev` (moved at most
// cut_camera_jump x `depth`, the frame's median view depth, 0 when not known; turned at most
// cut_camera_angle), else what it did ("camera moved 3.1 (median depth 2.4)").
std::string camera_cut(const Camera& prev, const Camera& cur, double depth, const Params& p);

// history_window `window` > 0: how many frame numbers before `frame` its accumulated values
// reach back (the age of the oldest chain that weighs in it; 0 to 2·window − 2). 0 for 0.
int window_memory(int window, int frame);

class TemporalChain {
 public:
  // Outputs "auto" are resolved on the first frame (resolve_frame_outputs).
  explicit TemporalChain(Params p);

  // The outputs of frame `frame` (its absolute number: it turns the slices, so that a chunk
  // of a sequence computes what the whole run computes). `cut`: drop the history first.
  AoFrame process(const GBuffer& g, const Camera& cam, int frame, bool cut,
                  const SH9* environment = nullptr, TemporalReport* report = nullptr);
  // The same, releasing each of g's fields once it has been used, so that a frame's input
  // does not stay in memory whole until its outputs are made (what a frame loop uses).
  AoFrame process(GBuffer&& g, const Camera& cam, int frame, bool cut,
                  const SH9* environment = nullptr, TemporalReport* report = nullptr);

  void reset() { has_history_ = false; }
  // The panorama of the frame processed next (Params::panorama; RadianceCache::set_panorama).
  void set_panorama(const GBuffer& pano, int frame) {
    cache_.set_panorama(pano, float(p_.background_depth), frame);
  }
  // Frame `frame`, ahead of its turn (Params::radiance_cache_ahead; RadianceCache::add_ahead),
  // in increasing order. `cut`: a cut given at it; else one is found from the jump of its
  // camera from `before`'s (the frame's before it; null: none known). Nothing without
  // radiance_cache_ahead.
  void look_ahead(const GBuffer& g, const Camera& cam, int frame, bool cut, const Camera* before);
  // Params::unseen_scale for the frames processed next (a calibrated level per frame).
  void set_unseen_scale(double s) { p_.unseen_scale = s; }
  // The calibrated fill level per surface for the frames processed next (FrameInputs::tiles),
  // or null; the caller keeps it alive while they are processed.
  void set_fill_tiles(const FillTiles* tiles) { tiles_ = tiles; }

  // Per-pixel history channels: irradiance (3, only when the outputs gather light), ao, vis,
  // bent vector in world space (3), n; with history_window, two such groups (the chains) and,
  // when gathering, the frame's own irradiance (3). What is not gathered is not carried, so
  // that ao and bentcone alone reproject 6 channels, not 9.
  static constexpr int kIrradianceChannels = 3;
  static constexpr int kOcclusionChannels = 6;

 private:
  // `release`: g itself, whose fields are freed after their last use; or null.
  AoFrame run(const GBuffer& g, GBuffer* release, const Camera& cam, int frame, bool cut,
              const SH9* environment, TemporalReport* report);
  Params p_;
  bool has_history_ = false;
  int width_ = 0, height_ = 0;  // the history's frame size
  ViewGBuffer view_;  // the history's view-space G-buffer (its searched texels, search_scale > 1)
  Camera cam_;        // and camera
  int frame_ = 0;     // and frame number
  std::vector<float> data_;  // the history channels per pixel (see above)
  const FillTiles* tiles_ = nullptr;
  RadianceCache cache_;  // what the last frames (and those ahead) showed
};

}  // namespace hbil
