// camera_io.h: where hbil gets each frame's camera from.
//
// Three sources, tried by the caller in this order:
//  1. a JSON sidecar "X.camera.json" next to "X.exr", written by
//     samples/blender/export_camera.py (format "hbil-camera-1", schema below);
//  2. the OpenEXR standard attributes worldToCamera / worldToNDC (other renderers);
//  3. a camera solved from the Position pass (world-space position of every pixel).
// Every source is converted once to hbil's own convention (hbil/camera.h): vision view
// space (+x right, +y down, +z forward), view = R * world + t, pixel (col, row) centre at
// raster (col + 0.5, row + 0.5), raster = (fx * x / z + cx, fy * y / z + cy).
//
// Errors: a camera that is present but unusable throws hbil::Error(Exit::camera, ...) with
// the file and the offending key; an unreadable sidecar file throws Exit::input.
//
// Sidecar schema "hbil-camera-1" (keys read here; other keys are ignored):
//   format        "hbil-camera-1"                              required
//   type          "PERSP" (ORTHO and PANO are not supported)   required
//   resolution    [width, height], rendered pixels             required
//   matrix_world  4 rows of 4 numbers: Blender cam.matrix_world required
//                 (camera -> world, camera looks down its local -Z, +Y up; scale ignored)
//   lens_mm, sensor_width_mm, sensor_height_mm (> 0)           required
//   sensor_fit    "AUTO" | "HORIZONTAL" | "VERTICAL"           required
//   pixel_aspect  pixel_aspect_y / pixel_aspect_x (> 0)        optional, default 1
//   shift_x, shift_y  lens shift, units of the larger side     optional, default 0
#pragma once

#include <OpenImageIO/imageio.h>

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hbil/camera.h"
#include "hbil/vecmath.h"

namespace hbil::io {

// "dir/frame_0001.exr" -> "dir/frame_0001.camera.json" (the extension, if any, is
// replaced; same rule as export_camera.py's sidecar_path).
std::string sidecar_path_for(const std::string& exr_path);

// Reads and converts a sidecar. Exit::input when the file cannot be read, Exit::camera
// for bad JSON, a missing key, a wrong type or value, or an unsupported camera type; the
// message starts with the path and names the key.
Camera camera_from_sidecar(const std::string& path);
// Same from parsed JSON; source_name prefixes error messages and fills Camera::source.
Camera camera_from_sidecar_json(const nlohmann::json& j, const std::string& source_name);

// Readers for JSON camera files (sidecars, POV-Ray camera files): every error is
// Error(Exit::camera, "<src>: key \"<key>\" ...").
[[noreturn]] void camera_file_error(const std::string& src, const std::string& msg);
const nlohmann::json& camera_file_key(const nlohmann::json& j, const char* key,
                                      const std::string& src);  // present
double camera_file_number(const nlohmann::json& v, const char* key,
                          const std::string& src);  // a finite number

// OpenEXR standard attributes (OIIO names "worldtocamera", "worldtoNDC", TypeMatrix44,
// float or double). Imath row-vector convention: p' = p * M, translation in the last row.
//  worldToCamera: camera space left-handed, +x right, +y up, +z forward.
//  worldToNDC:    NDC (0,0) = top-left, (1,1) = bottom-right corner of the display window.
// The camera refers to the data window: Camera::width/height = spec.width/height and the
// principal point is shifted by the display-window origin minus the data-window origin.
// nullopt when worldToCamera or worldToNDC is absent or not a pinhole projection;
// camera_attribute_status() says which.
std::optional<Camera> camera_from_exr_attributes(const OIIO::ImageSpec& spec);
// One line for logs and error messages, e.g. "worldToCamera present, worldToNDC missing
// (intrinsics unknown)" or "worldToCamera and worldToNDC: pinhole fx=... fy=...".
std::string camera_attribute_status(const OIIO::ImageSpec& spec);
// The inverse: sets "worldtocamera" and "worldtoNDC" (TypeMatrix44) from a camera whose
// width/height are the display window (spec.full_width/height). NDC z is 1 / view z.
void set_camera_attributes(OIIO::ImageSpec& spec, const Camera& camera);

// Pinhole camera (no skew; fx and fy solved independently) from world-space positions at
// pixel centres. positions: width * height, row-major, rows top-down (as the Position
// pass is stored). Exactly (0,0,0) or non-finite = background, skipped.
// Method: normalised DLT (Hartley & Zisserman, "Multiple View Geometry", 2nd ed., Alg. 7.1)
// for the 3x4 projection P, P = K [R | t] by RQ (H&Z 6.2.4), then Levenberg-Marquardt on
// (fx, fy, cx, cy, R, t) minimising the reprojection error, with iterative outlier
// rejection (pixels farther than clamp(4 * median residual, 0.01, 2) px are dropped, then
// solved again). At most kSolveMaxPixels pixels, evenly strided, take part.
// Sets reprojection_rms_px (RMS over the inliers, final camera) and
// source = "solved from Position (N pixels)".
// Throws Exit::camera with fewer than kSolveMinPixels usable pixels or inliers, or when the
// points are (nearly) coplanar or collinear.
inline constexpr int kSolveMinPixels = 100;
// 20000: on the 1920x1080 renders of the samples the camera solved from 200000 pixels and
// from 20000 differ by < 0.01 px in reprojection (tests/camera_io_test.cpp), at a tenth of
// the time.
inline constexpr int kSolveMaxPixels = 20000;
// A frame whose sampled positions equal the last solved frame's bit for bit gets that camera
// again without a solve (the solve is deterministic).
Camera solve_camera_from_positions(int width, int height, const std::vector<Vec3>& positions);
// Solves actually run in this process (for tests of the reuse above).
int camera_solves();

}  // namespace hbil::io
