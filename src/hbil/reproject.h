// reproject.h: brings the previous frame's per-pixel data into the current view (HBIL §3.2).
//
// Both functions are generic over `channels` floats per pixel, so one call moves radiance,
// irradiance, AO, bent normals, history length, ... together. Images are rows top-down,
// `channels` floats per pixel, pixel-major (value[i * channels + c]).
//
// Acceptance ("same surface") compares the previous frame's point with the current pixel:
//  - depth: the point's distance (scatter: current-view depth difference; gather: world
//    distance) is at most tol.depth * z_current;
//  - normal: the world-space normals (view normals through each camera's view_dir_to_world)
//    have dot >= tol.normal_cos.
// Background pixels (ViewGBuffer::is_background) are never sources and never valid. Invalid
// pixels hold 0 in every channel.
//
// Results depend only on the inputs, never on the number of threads: per-row work is
// parallel, the scatter's z-buffer resolve is serial in source order (ties in depth go to the
// smallest source index), and every per-pixel sum runs in a fixed order.
#pragma once

#include <cstdint>
#include <vector>

#include "hbil/camera.h"
#include "hbil/gbuffer.h"

namespace hbil {

struct Reprojected {
  int width = 0, height = 0, channels = 0;
  std::vector<float> value;    // width*height*channels, current-frame pixels; 0 where invalid
  std::vector<uint8_t> valid;  // 1 where a previous-frame value was found and accepted
};

struct ReprojectTolerance {
  float depth = 0.05f;      // relative to the current pixel's view z (see above)
  float normal_cos = 0.8f;  // world normals must agree: dot >= normal_cos (~37 degrees)
};

// Scatter (both cameras known): every non-background previous pixel's world point
// (prev_cam.view_to_world(prev.position)) is projected with cur_cam and lands on the current
// pixel whose square contains that raster position (points behind the current camera or off
// the image are dropped). A z-buffer keeps, per current pixel, the landed point of smallest
// current-view z. The current pixel is valid when something landed, |z_landed - z_cur| <=
// tol.depth * z_cur and the world normals agree; it then takes that source pixel's channels
// unchanged (nearest neighbour, no interpolation). Splat gaps (magnification, disocclusion)
// stay invalid: fill them with push_pull (pushpull.h).
// prev_value must hold prev.pixels() * channels floats; prev and cur may differ in size.
// A reduced cur (ViewGBuffer::scale f > 1, reduce_view) has a texel per f x f block of the
// camera's pixels: a point lands on the texel whose block holds its raster position.
Reprojected reproject_scatter(const ViewGBuffer& prev, const Camera& prev_cam,
                              const std::vector<float>& prev_value, int channels,
                              const ViewGBuffer& cur, const Camera& cur_cam,
                              const ReprojectTolerance& tol = {});

// Gather through motion vectors: motion holds 2 floats per current pixel, the raster offset
// (du, dv) from the current pixel's centre to where its surface point was in the previous
// frame, i.e. previous raster (col + 0.5 + du, row + 0.5 + dv) (GBuffer::motion). The value
// is the bilinear interpolation of the (up to) 4 previous pixels around that raster position,
// using only those inside the previous image, not background, whose world point lies within
// tol.depth * z_cur (Euclidean) of the current pixel's world point and whose world normal
// agrees; the remaining bilinear weights are renormalised. Invalid when no neighbour with a
// positive weight passes, or when the motion is not finite. cur_cam places the current
// pixel in the world; motion must hold cur.pixels() * 2 floats.
Reprojected reproject_gather(const ViewGBuffer& prev, const Camera& prev_cam,
                             const std::vector<float>& prev_value, int channels,
                             const ViewGBuffer& cur, const Camera& cur_cam,
                             const std::vector<float>& motion, const ReprojectTolerance& tol = {});

}  // namespace hbil
