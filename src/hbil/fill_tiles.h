// fill_tiles.h: a calibrated fill level that varies over the shot's surfaces
// (Params::calibration_tiles).
//
// A calibration render tells the mean of the indirect light over each tile of a grid over its
// frame, not only over the frame (pipeline/calibration.h solves a factor per tile, relative to
// the frame's). A surface point takes the factor of the tile it lies in, seen from that
// calibration frame's camera: bilinear between tile centres, clamped at the frame's edges, so
// that the factor belongs to the surface and follows it through a camera move. Frame f takes
// the weighted mean of the calibration frames around it that see the point (the weights of the
// frame's own factor, Calibration::scale_at), and 1 where none does.
#pragma once

#include <vector>

#include "hbil/camera.h"
#include "hbil/vecmath.h"

namespace hbil {

struct FillTiles {
  struct View {
    Camera cam;             // the calibration frame's camera, as its tiles are measured
    double x0 = 0, y0 = 0;  // its display window in cam's raster: origin and size
    double w = 0, h = 0;
    int cols = 0, rows = 0;
    std::vector<float> factor;  // rows x cols, row-major: each tile's factor
    double weight = 1;          // its weight for the frame
  };
  std::vector<View> views;

  bool empty() const { return views.empty(); }
  // The factor at world position p.
  float at(const Vec3d& p) const;
};

}  // namespace hbil
