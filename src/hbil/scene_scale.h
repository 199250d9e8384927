// scene_scale.h: parameters that fit the shot, with no reference: gather_radius, thickness
// and gather_thickness "auto" are derived from the G-buffer of the shot's first frame, once
// per run (pipeline::SequenceJob takes the sequence's first frame on disk, whatever
// --frames says), so that every frame of a run, and every chunk of a shot, uses the same
// values.
//
//  - gather_radius "auto": the width of the frame at the median depth of its geometry
//    pixels, width_px * median_depth / fx. The gather then reaches across what the frame
//    shows at the distance where most of it is; the search is clipped to the image anyway,
//    so a larger reach would only thin out the gather's samples.
//  - thickness "auto": kAutoThickness times that median depth, at most kAutoThicknessOfRadius
//    x radius: the samples within radius, which make ao, see occluders of the size ao is
//    about (where the back-face layer gives a pixel its own thickness, this is only the value
//    for pixels without one).
//  - gather_thickness "auto": kAutoThickness times the median depth, uncapped: the samples
//    beyond radius, seen only by the gather, are the walls and buildings of the scene.
//    Where thickness is a number, gather_thickness "auto" is that number.
//
// Both scale with the scene: a tabletop seen from 0.5 m and a street seen from 20 m get
// the same result in units of what the frame shows.
#pragma once

#include <string>

#include "hbil/camera.h"
#include "hbil/gbuffer.h"
#include "hbil/params.h"

namespace hbil {

// Fitted on room_poles and courtyard without their back-face layers (README "Defaults that
// fit the scene"): 0.4 x radius is the constant once tuned on both rooms' ao; the gather's
// factor is the best of 0.075, 0.15, 0.3, 0.6 and 1.2 on both rooms' indirect light.
inline constexpr double kAutoThickness = 0.15, kAutoThicknessOfRadius = 0.4,
                        kAutoGatherThickness = 0.3;

struct SceneScale {
  size_t geometry = 0;  // pixels with depth below background_depth
  double depth_p10 = 0, depth_median = 0, depth_p90 = 0;  // planar depth, world units
  double width_at_median = 0;                             // frame width there, world units
};

// The depth percentiles of g's geometry pixels (from depth, else from position through the
// camera). geometry == 0 when the frame shows only background.
SceneScale measure_scene(const GBuffer& g, const Camera& cam, const Params& p);

// `p` with gather_radius, thickness and gather_thickness "auto" replaced by their values for this
// scene (a frame with no geometry keeps the numbers `p` holds). `why` gets one line saying what was
// chosen and from what ("" when nothing was auto).
Params resolve_scene_params(const Params& p, const SceneScale& s, std::string* why = nullptr);

}  // namespace hbil
