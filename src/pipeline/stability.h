// stability.h: `hbil bench --stability`: how a configuration behaves where screen-space
// methods are known to fail, measured on the user's own shot and references. Each figure is
// defined in the man page (bench, "Stability"):
//
//  - flicker: the shot's first frame repeated (a static camera), mean |L_k − L_(k−1)| over
//    mean L of the judged layer, frames 2..6, over geometry pixels;
//  - revealed: RMSE on pixels newly revealed (history.Y = 1 after the first frame) and on
//    the others, against the reference;
//  - cut: the shot's last frame on disk put before its first ones, whether the cut was
//    detected, and the frames after it until the result is the uncut run's (relative RMSE
//    below 1e-3);
//  - edge: RMSE in the band of 5 % of the shorter side along the frame's border, and inside;
//  - thin: RMSE on thin objects (geometry no wider than 6 pixels, across which the depth
//    rises by 10 % on both sides, horizontally or vertically) and on the rest;
//  - robustness: zero normals injected into 1 % of the first frame's pixels (every output
//    value must stay finite), NaN and infinite depth and NaN colour (each must be refused
//    with exit 5 and no output).
#pragma once

#include <string>

#include "pipeline/bench.h"

namespace hbil::pipeline {

// StabilityFigures (bench.h): one configuration's figures on the layer of `ref`, over the frames of
// `s` (its shot, frames and mask). Temporary sequences go under `scratch`.
StabilityFigures measure_stability(const BenchSettings& s, const BenchConfig& c,
                                   const BenchReference& ref, const std::string& scratch);

}  // namespace hbil::pipeline
