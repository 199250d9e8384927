// unseen.h: what the gather's empty directions see with unseen_radiance "auto".
//
// The directions in which the search finds nothing (off screen, or beyond gather_radius)
// see either a surface the frame does not show or the render's background (the sky, whose
// light Cycles and POV-Ray count as direct). Which, the G-buffer says only for the
// directions the camera sees: its background pixels are lines of sight that escape. "auto"
// takes the frame's escape fraction per band of elevation (the angle above the image's
// horizontal, in view space). The bands the frame does not reach say nothing, so they
// escape; or, for enclosed shots (unseen_carry), the frame's top edge says how open the
// space above it is, and its bottom edge the space below: the share of the edge rows that
// is background or a surface facing that way (an open sky at the top of the frame stays
// open above it, a wall or a ceiling closes it, a floor seen from above leaves it open). A
// pixel with normal n then sees, in its empty directions,
//
//   fill(n) = factor x (mean direct outgoing radiance of the frame's geometry)
//             x (1 − the cosine-weighted escape fraction over n's hemisphere),
//
// (factor: auto_unseen_factor, ao_frame.h) so that a ground plane under open sky gets almost
// nothing, and a room whose walls the frame shows gets the whole fill for the elevations it shows
// (all of them with unseen_carry).
#pragma once

#include <array>
#include <vector>

#include "hbil/camera.h"
#include "hbil/gbuffer.h"
#include "hbil/vecmath.h"

namespace hbil {

// The fraction of lines of sight that escape (background pixels), per band of
// sin(elevation) over [-1, 1] (band 0 looks straight down, kBands - 1 straight up). The
// bands the frame does not reach escape (1), or with `carry` take what its top edge rows
// (the top 1/16) say of the space above them and its bottom edge rows of the space below:
// background, and surfaces facing up at the top or down at the bottom, are open (a ramp
// over the normal's up component from 0.3 to 0.7). Each pixel counts with its solid angle.
// A frame without pixels reaches no band.
struct EscapeProfile {
  static constexpr int kBands = 16;
  std::array<float, kBands> open{};
  int lowest_seen = 0, highest_seen = 0;  // the bands the frame reaches
};
// `v`: the full-resolution view G-buffer, `cam` its camera (raster = v's pixel grid).
EscapeProfile escape_profile(const ViewGBuffer& v, const Camera& cam, bool carry);

// The cosine-weighted escape fraction over the hemisphere of a unit view-space normal n
// (it depends only on n's elevation: kTable entries over sin(elevation), interpolated).
class EscapeTable {
 public:
  static constexpr int kTable = 65;
  explicit EscapeTable(const EscapeProfile& profile);
  float at(const Vec3& n) const;

 private:
  std::array<float, kTable> table_{};
};

// The fill per pixel of the searched view `sv` (possibly reduced: only its normals and
// background are read): `fill` x (1 − the escape fraction over each normal's hemisphere);
// zero on background. The same for any thread count.
std::vector<Vec3> unseen_fill_map(const ViewGBuffer& sv, const EscapeProfile& profile,
                                  const Vec3& fill);

// With the renderer's escape pass (GBuffer::escape) the frame need not guess. Per pixel, e is
// the cosine-weighted fraction of its hemisphere from which no surface of the whole scene is
// hit, and a the fraction the screen-space search leaves unblocked within its reach (its ao).
// Of the directions the search finds empty, a surface it cannot see blocks the fraction
// 1 − e / a, and what they see is
//
//   fill x clamp(1 − e / a, 0, 1)
//
// in place of fill x (1 − the frame's escape fraction): nothing over a table top in a void or
// a ground plane under an open sky, the whole fill in a closed room, and, beside an object the
// search does see, only what lies beyond it (e and a both count that object).
//
// `escape`: e at the searched view's pixels (escape_at_view); `reach`: a at the same pixels.
// Background pixels 0. The same for any thread count.
std::vector<Vec3> escape_fill_map(const ViewGBuffer& sv, const std::vector<float>& escape,
                                  const std::vector<float>& reach, const Vec3& fill);
// The escape pass `e` (one value per pixel of v, the full-resolution view, clamped to [0, 1])
// at the pixels of sv = reduce_view(v, f) (f = 1: sv is v): the mean of e over the pixels of v
// within r = max(kEscapeRadius, f / 2) of each texel's own pixel, on its surface (the
// spatial filter's test), so that a pass rendered with one sample per pixel will do.
constexpr int kEscapeRadius = 2;
std::vector<float> escape_at_view(const ViewGBuffer& v, const ViewGBuffer& sv, int f,
                                  const std::vector<float>& e, float depth_tolerance);

}  // namespace hbil
