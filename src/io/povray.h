// povray.h: reading the passes that samples/povray/hbil.inc renders, one frame at a time,
// and turning them into a G-buffer frame with Blender's layer names.
//
// POV-Ray has no render passes and writes half-float OpenEXR only, so hbil.inc renders one
// emission-only pass per G-buffer field (render_gbuffer.sh names them <pass><frame>.exr):
//   depth      R, G, B = three 11-bit digits of planar depth / depth_range, A = coverage
//   normal     R, G, B = slope{x}, slope{y}, slope{z} = 1 - angle(N, axis) / pi
//   albedo     diffuse albedo                        -> DiffCol
//   emit       emission where an object is, the sky where none is -> Emit, Env
//   direct     white diffuse surfaces under the scene's lights -> DiffDir
//   backfaces  depth digits of the first back face (0 = none) -> BackFaces.Depth.Z
//   reference  radiosity render                      -> Combined.RGB, DiffInd
// and camera<frame>.json ("hbil-povray-camera-1": location, direction, right, up in POV-Ray
// space, width, height, depth_range), written by the scene itself.
//
// POV-Ray's space is left-handed with +y up; hbil's worlds are Blender's (right-handed,
// +z up). pov_to_world() is the one place where one becomes the other: (x, y, z) ->
// (x, z, y), a reflection that also turns the handedness.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "hbil/camera.h"
#include "hbil/vecmath.h"

namespace hbil::io {

// POV-Ray (left-handed, y up) -> hbil world (right-handed, z up).
constexpr Vec3d pov_to_world(const Vec3d& p) {
  return {p.x, p.z, p.y};
}

// The camera file of one frame, as written by hbil.inc (POV-Ray space).
struct PovrayCamera {
  int frame = 0;
  double clock = 0;
  int width = 0, height = 0;
  // An overscan's guard band (render_gbuffer.sh --overscan): the frame as framed is the
  // width - 2 guard_x by height - 2 guard_y pixels in the middle.
  int guard_x = 0, guard_y = 0;
  double depth_range = 0;
  Vec3d location, direction, right, up;
  // A panorama (render_gbuffer.sh --panorama): the passes are an equirectangular image from
  // `location` over the whole sphere, and the depth pass holds the distance from it.
  bool panorama = false;
};
// Throws Error(Exit::input) when the file cannot be read, Error(Exit::camera) for a bad
// format, missing key, or a camera that is not an orthogonal perspective camera with square
// pixels (the message names the file and the key).
PovrayCamera read_povray_camera(const std::string& path);
// The pinhole camera in hbil's conventions; pixel centres as POV-Ray traces them without
// anti-aliasing: ray = direction + ((col + 0.5) / W - 0.5) right + (0.5 - (row + 0.5) / H) up.
Camera camera_from_povray(const PovrayCamera& c, const std::string& source);

// Planar depth from the depth pass's digits: (round(2048 r) + (round(2048 g) + b) / 2048)
// / 2048 * range.
double decode_povray_depth(float r, float g, float b, double range);
// World-space (hbil) unit normal from slope{x}, slope{y}, slope{z} values; zero when the
// three values do not describe a direction (e.g. background).
Vec3 decode_povray_normal(float sx, float sy, float sz);

// The files of one frame found in a pass folder: pass name -> path, and the camera file.
struct PovrayFrameFiles {
  int frame = 0;
  std::string camera;
  std::map<std::string, std::string> passes;
};
// Scans `dir` for <pass><digits>.exr and camera<digits>.json (no digits = frame 0), by
// frame. With `reference_dir`, the reference passes come from that folder instead (e.g. a
// second radiosity render with fewer bounces). Throws Error(Exit::input) when a folder
// cannot be read or `dir` holds no depth pass.
std::vector<PovrayFrameFiles> find_povray_frames(const std::string& dir,
                                                 const std::string& reference_dir = "");

// One imported frame: channels named like a Blender 3.4 multilayer EXR.
struct ImportedFrame {
  int width = 0, height = 0;
  int guard_x = 0, guard_y = 0;  // the camera file's: the EXR's data window starts at -guard
  std::vector<std::string> channels;
  std::vector<float> pixels;        // interleaved, rows top-down
  Camera camera;                    // not set for a panorama
  bool panorama = false;            // PovrayCamera::panorama
  std::vector<std::string> layers;  // pass names written, for the log
};
// Reads and converts the passes of one frame: depth, normal and the camera are required
// (Error(Exit::missing_pass) / Error(Exit::camera)), the others are used when present.
// Every pass must have the camera's resolution (Error(Exit::bad_data), naming the file).
// Layers (view layer `view_layer`):
//   Depth.Z (1e10 on the background), Normal.X/Y/Z (world space, towards the camera),
//   Combined.A (coverage) [+ Combined.R/G/B from reference], DiffCol, DiffDir, Emit, Env,
//   DiffInd = (Combined - DiffCol * DiffDir - Emit - Env) / DiffCol (0 where DiffCol is 0,
//   as Cycles divides its light passes), and BackFaces.Depth.Z in the view layer
//   "BackFaces" (1e10 where the ray leaves through no back face).
// A panorama's camera file (PovrayCamera::panorama) makes the frame a panorama for hbil's
// `panorama` key: Position.X/Y/Z (world) and Depth.Z (the distance from the camera's
// location; 1e10 on the background) from the depth pass along the directions of the
// equirectangular image (equirect_to_direction, the convention of `environment`: the centre
// column looks along +X, a quarter to its left along +Y, the top row at the zenith),
// Combined.A, DiffCol, DiffDir, Emit and Env as above; no normal pass is needed, and no camera
// is written.
ImportedFrame import_povray_frame(const PovrayFrameFiles& files,
                                  const std::string& view_layer = "ViewLayer");

}  // namespace hbil::io
