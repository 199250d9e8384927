// camera.h: the pinhole camera every stage of hbil works with.
//
// Conventions (the only ones used inside hbil; every loader converts to them once):
//  - view space is right-handed "vision" space: +x right, +y down (along image rows),
//    +z forward. A point's planar depth is its view-space z.
//  - pixel (col, row) of an image, rows top-down as stored in EXR, has its centre at
//    raster position (col + 0.5, row + 0.5).
//  - view = R * world + t;  raster = (fx * x / z + cx, fy * y / z + cy).
#pragma once

#include <string>

#include "hbil/vecmath.h"

namespace hbil {

struct Camera {
  int width = 0, height = 0;       // resolution the intrinsics refer to, pixels
  double fx = 1, fy = 1;           // focal length, pixels
  double cx = 0, cy = 0;           // principal point, raster coordinates (pixels)
  Mat3d R;                         // world -> view rotation
  Vec3d t;                         // world -> view translation
  std::string source;              // where it came from, e.g. "sidecar frame_0001.camera.json"
  double reprojection_rms_px = 0;  // RMS reprojection error when solved from Position

  Vec3d world_to_view(const Vec3d& p) const { return R * p + t; }
  Vec3d view_to_world(const Vec3d& v) const { return R.transposed() * (v - t); }
  Vec3d view_dir_to_world(const Vec3d& d) const { return R.transposed() * d; }
  Vec3d world_dir_to_view(const Vec3d& d) const { return R * d; }
  // Camera centre in world space.
  Vec3d centre() const { return R.transposed() * (-t); }
  // View-space point of the pixel at raster (u, v) with planar depth z.
  Vec3d unproject(double u, double v, double z) const {
    return {(u - cx) / fx * z, (v - cy) / fy * z, z};
  }
  // Raster position of a view-space point (z must be > 0).
  void project(const Vec3d& pv, double& u, double& v) const {
    u = fx * pv.x / pv.z + cx;
    v = fy * pv.y / pv.z + cy;
  }
};

}  // namespace hbil
