// gbuffer.h: the G-buffer as read from a frame, and its view-space form for the kernels.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hbil/camera.h"
#include "hbil/params.h"
#include "hbil/vecmath.h"

namespace hbil {

// Fields as stored by the renderer (Blender: Depth planar, Normal and Position world
// space). A field that was not read is empty: hbil reads only what the outputs need.
struct GBuffer {
  int width = 0, height = 0;
  std::vector<float> depth;      // planar view depth, world units
  std::vector<float> backdepth;  // planar depth of the first back face behind it (optional)
  std::vector<Vec3> normal;      // world space, pixel-filtered (may be shorter than 1)
  std::vector<Vec3> position;    // world space
  std::vector<float> alpha;      // coverage; 0 = background
  std::vector<Vec3> diffcol;     // diffuse albedo (Blender DiffCol)
  std::vector<Vec3> diffdir;     // direct diffuse irradiance / π (Blender DiffDir)
  std::vector<Vec3> emit;        // emitted radiance (Blender Emit)
  // Whether emit is light the gather adds (Params::emission): false where diffdir already
  // holds what the emitting surfaces cast (Cycles), so that emit is only the composite's.
  bool emit_gathered = false;
  std::vector<Vec3> f0;         // reflectance at normal incidence (optional, HBIL eq. 19)
  std::vector<float> metallic;  // metalness in [0, 1] (optional, used when f0 is absent)
  // Raster offset (du, dv) per pixel from its centre to where its surface was in the
  // previous frame (from Blender's Vector pass), 2 floats per pixel.
  std::vector<float> motion;
  // The cosine-weighted fraction of each pixel's hemisphere from which no surface of the whole
  // scene is hit (Cycles' AO pass rendered with World > Ambient Occlusion > Distance beyond
  // the scene); optional, read by unseen_radiance "auto" (unseen.h).
  std::vector<float> escape;
  // Passed through into the composite when present (Blender names: Env, GlossCol, ...).
  std::vector<Vec3> env, glosscol, glossdir, glossind, transcol, transdir, transind;

  // Colour fields the file stores as 16-bit floats can be kept in that form until unpack()
  // (io::read_fields with keep_half): half their memory while the frame waits to be
  // computed and while its geometry is; unpacking gives the floats a direct read gives.
  // Each entry: the field's name and its 3 samples per pixel as IEEE half bits.
  std::vector<std::pair<std::string, std::vector<std::uint16_t>>> packed;
  // Whether the colour fields that can be packed (diffcol, diffdir, emit, env and the glossy
  // and transmission passes) include this one.
  static bool packable(const std::string& field);
  // Converts every packed field into its RGB array, one at a time.
  void unpack();

  // The RGB field of that G-buffer field name (diffcol, env, ...), or null.
  std::vector<Vec3>* rgb(const std::string& field);
  // Whether that field was read (packed or not).
  bool has(const std::string& field) const;

  // The display window in this raster's pixels: where the frame is framed; the rest is guard
  // band (an overscan). display_width 0: the whole raster.
  int display_x = 0, display_y = 0, display_width = 0, display_height = 0;
  bool in_display(int x, int y) const {
    return display_width <= 0 || (x >= display_x && x < display_x + display_width &&
                                  y >= display_y && y < display_y + display_height);
  }

  size_t pixels() const { return size_t(width) * size_t(height); }

  // Outgoing diffuse radiance at pixel i (unpacked) with irradiance / π `e` there: DiffCol x e,
  // + Emit where emit_gathered.
  Vec3 outgoing(size_t i, const Vec3& e) const {
    Vec3 l{diffcol[i].x * e.x, diffcol[i].y * e.y, diffcol[i].z * e.z};
    if (emit_gathered && !emit.empty()) l += emit[i];
    return l;
  }
};

// The float an IEEE 754 half (binary16) with these bits stands for, exactly (every half is
// a float); NaN payloads are kept, as OpenEXR's conversion keeps them.
float half_to_float(std::uint16_t bits);

// What the horizon search reads: view-space position and unit view-space normal per
// pixel, rows top-down. A background pixel has position.z = +infinity and a zero normal.
struct ViewGBuffer {
  int width = 0, height = 0;
  std::vector<Vec3> position;
  std::vector<Vec3> normal;
  // Occluder thickness along each pixel's view ray, world units, from the back-face depth
  // (or, without one, from the object's extent on screen: thickness_from_extent); empty
  // without either; negative where it says nothing (the constant thickness applies).
  std::vector<float> thickness;
  // Full-resolution pixels per pixel of this buffer along x and y: 1, or f for a buffer made by
  // reduce_view (reduced.h) from every f-th pixel of every f-th row.
  int scale = 1;

  size_t pixels() const { return size_t(width) * size_t(height); }
  bool is_background(size_t i) const { return !(position[i].z < kBackground); }
  static constexpr float kBackground = 3.0e38f;
};

// Builds the view-space G-buffer. Position comes from depth when depth was read, else
// from the world position through the camera. Background: depth >= background_depth,
// alpha == 0, or a normal of zero length. Normals are renormalised (Blender averages
// them across silhouettes, so their length can fall to 0.25). With a back-face depth zb and
// front depth zf (both planar), thickness = |P| (zb − zf) / zf, the length of the pixel's ray
// inside the object; where zb is background or not behind zf by more than 0.1 % (the
// visible surface is itself a back face, or a single-sided surface), it is −1. Without a
// back-face layer, with p.thickness_extent and the bitmask method, thickness_from_extent.
ViewGBuffer make_view_gbuffer(const GBuffer& g, const Camera& cam, const Params& p);
// gbuffer_simd.cpp: make_view_gbuffer's pixels of row y from a depth pass, from x = 0 in whole
// SIMD vectors (the number done), into v (sized, its thickness too where g has a back-face
// depth); with p.vectorised, make_view_gbuffer takes them from it (the same values to the bit).
int view_row_from_depth(const GBuffer& g, const Camera& cam, double background_depth, int y,
                        ViewGBuffer& v);

// Without a back-face layer, an object is taken to be as thick as it is wide, up to
// `at_most` (the constant thickness): each geometry pixel's thickness is the smaller of the
// world extents of its surface's run along its row and along its column (pixels x depth /
// focal length), at most at_most; a pixel both of whose runs reach the image's edge says
// nothing (-1: the constant applies). A run ends where a neighbour leaves the tangent plane
// by more than depth_tolerance x depth. The march treats it as a measured thickness.
void thickness_from_extent(ViewGBuffer& v, const Camera& cam, float depth_tolerance, float at_most);

// The pixels that are background only because their normal has zero length (all three
// components 0): covered (alpha > 0 or no alpha), in front of the background (depth below
// background_depth, or without depth a non-zero position), yet without a direction. Blender
// writes such normals nowhere but the background, so they mark a broken or foreign normal
// pass; make_view_gbuffer takes them for background (they neither receive nor occlude) and
// the caller warns. `first`: the lowest such pixel index (valid when count > 0).
struct ZeroNormals {
  size_t count = 0;
  size_t first = 0;
};
ZeroNormals find_zero_normals(const GBuffer& g, const Params& p);

}  // namespace hbil
