// reduced.h: the horizon search at a reduced resolution, and the depth- and normal-aware
// upsample of its result (Params::search_scale).
//
// Occlusion and indirect light vary slowly across a surface: at 1920x1080 the default AO
// radius spans hundreds of pixels and its 16 steps per side lie tens of pixels apart, so a
// search on every f-th pixel of every f-th row sees nearly the same occluders as one on
// every pixel, for 1/f² of the cost. Texel (i, j) of the reduced buffer is the full-resolution
// pixel (f i, f j) itself (position, normal and thickness unchanged, not averaged), so the
// reduced grid is the full one with a spacing of f pixels and the march's ray geometry stays
// exact (ViewGBuffer::scale). The source radiance of a texel is the mean over its f x f block
// of the pixels on the texel's own surface (its 1-spp noise averaged, never light from another
// surface).
//
// Upsample (a joint bilateral upsample, Kopf et al. 2007): each full-resolution pixel takes
// the bilinear weights of the 2x2 texels around its position, kept only for texels on its own
// surface (the spatial filter's test: within depth_tolerance x z of its tangent plane, normal
// within 37 degrees). A pixel with none of them (a surface narrower than f pixels, such as a
// pole seen from afar) takes the texel of the 4x4 around it that lies nearest its tangent
// plane among those facing its way, else the unoccluded default.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hbil/gbuffer.h"
#include "hbil/interleave.h"

namespace hbil {

// search_scale 0 ("auto") searches on every n-th pixel with the largest n that keeps at
// least this many pixels across the frame's shorter side (measured in README "Speed": at
// 1920x1080, n = 2 changes ao, indirect and composite by less than the reference renders'
// noise; at 256x144 any n > 1 costs up to 1.7 dB of AO).
constexpr int kAutoSearchSide = 540;
// Params::search_scale resolved for a frame of width x height (the value itself when >= 1).
int effective_search_scale(const Params& p, int width, int height);
// What the search does on such a frame, for logs: "every pixel", "one pixel of every 2x2
// block, upsampled (search_scale auto for 1920x1080)".
std::string describe_search(const Params& p, int width, int height);

// The texels searched across n pixels with search_scale f: pixels 0, f, 2f, ... (f >= 1).
constexpr int reduced_extent(int n, int f) {
  return (n + f - 1) / f;
}
// Every f-th pixel of every f-th row of v (f >= 1), with scale = v.scale * f: a view of
// reduced_extent(v.width, f) x reduced_extent(v.height, f) texels.
ViewGBuffer reduce_view(const ViewGBuffer& v, int f);
// The motion (GBuffer::motion, 2 floats a pixel of v) of each texel of lo = reduce_view(v, f):
// its own pixel's, in texels (divided by f).
std::vector<float> reduce_motion(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                                 const std::vector<float>& motion);
// The source radiance of each texel of `lo` (from reduce_view(v, f)): the mean of L over the
// pixels of its f x f block of v on the texel's surface (surface_mean; its own pixel's where
// none is, as with a degenerate normal).
std::vector<Vec3> reduce_radiance(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                                  const std::vector<Vec3>& L, float depth_tolerance);
// The search result `h` on `lo` brought to v's resolution (background pixels keep the
// unoccluded default: ao = vis = 1, bent = 0, irradiance = 0).
HorizonImage upsample_horizon(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                              const HorizonImage& h, float depth_tolerance);

// Which texels of lo each pixel of v takes in the upsample, decided once for the searches of a
// frame that share its geometry (the in-frame bounces): per pixel kNone (background, or no
// texel facing its way), kBilinear | a mask of the 2x2 texels on its surface (bit 2 dj + di),
// or the index of the one texel it takes.
struct UpsamplePlan {
  static constexpr std::uint32_t kNone = 0xffffffffu, kBilinear = 0x80000000u;
  int f = 1;
  std::vector<std::uint32_t> choice;
};
UpsamplePlan plan_upsample(const ViewGBuffer& v, const ViewGBuffer& lo, int f,
                           float depth_tolerance);
// upsample_horizon by a plan: the same result to the bit.
HorizonImage upsample_horizon(const ViewGBuffer& v, const ViewGBuffer& lo, const UpsamplePlan& plan,
                              const HorizonImage& h);
// A count per texel of lo (the chain's history length) brought to v by a plan: each pixel takes
// the value of the texel it weighs most among those the plan gives it, so that counts stay
// whole numbers; background pixels get 0, other pixels the plan gives no texel 1.
std::vector<float> upsample_count(const ViewGBuffer& v, const ViewGBuffer& lo,
                                  const UpsamplePlan& plan, const std::vector<float>& x);

}  // namespace hbil
