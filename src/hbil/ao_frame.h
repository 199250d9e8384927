// ao_frame.h: the per-frame AO and bent-cone chain, from G-buffer to output values.
//   view-space G-buffer -> horizon search (interleaved or full) -> spatial filter ->
//   ao (eq. 9-11), bent normal in world space (eq. 4-6), cone cosine (eq. 12).
#pragma once

#include <vector>

#include "hbil/camera.h"
#include "hbil/farfield.h"
#include "hbil/fill_tiles.h"
#include "hbil/gbuffer.h"
#include "hbil/interleave.h"
#include "hbil/params.h"
#include "hbil/radiance_cache.h"
#include "hbil/reduced.h"

namespace hbil {

struct AoFrame {
  int width = 0, height = 0;
  std::vector<float> ao;        // cosine-weighted visibility (eq. 9), 1 = unoccluded
  std::vector<Vec3> bent;       // unit bent normal, world space (eq. 4-6)
  std::vector<float> cone_cos;  // cos of the bent cone's half-angle, 1 − Ω/2π (eq. 12)
  // With the outputs irradiance or indirect (empty otherwise):
  std::vector<Vec3> irradiance;  // E_near / π: the units of Blender's DiffInd (× diffuse_weight)
  std::vector<Vec3> indirect;    // DiffCol × E_near / π: comparable to DiffCol × DiffInd
  std::vector<Vec3> ao_rgb;      // ao_multibounce: multi-bounce AO per channel
  std::vector<Vec3> farfield;    // far-field irradiance / π in the bent cone (§2.2.4)
  std::vector<Vec3> composite;   // premultiplied like Blender's passes
  std::vector<float> composite_alpha;  // its alpha (the input's); empty: 1 everywhere
  std::vector<float> history;  // temporal chain: frames accumulated per pixel (0: background)
};

// The diffusely reflected radiance a pixel sends to its neighbours (HBIL eq. 16-17):
// DiffCol × (DiffDir + irradiance), + Emit where g.emit_gathered (Params::emission), with
// irradiance = E/π of the previous bounce (empty: none yet).
std::vector<Vec3> source_radiance(const GBuffer& g, const std::vector<Vec3>& irradiance);

// The receiver's weight on diffusely reflected light, HBIL eq. 19: 1 − F0 per channel from
// g.f0, else 0.96 (1 − metallic) (F0 = 0.04 for dielectrics, ~1 for metals), else 1.
Vec3 diffuse_weight(const GBuffer& g, size_t i);
// e[i] times diffuse_weight(g, i) at every pixel; nothing where g has neither f0 nor metallic.
void weigh_diffuse(const GBuffer& g, std::vector<Vec3>& e);

// Outputs "auto" (Params::outputs) resolve to ao and bentcone, plus irradiance, indirect and
// composite when `g` holds DiffCol and DiffDir.
// Background pixels get ao = 1, bent = the input normal as stored (zero for Blender's
// background) and cone_cos = 0 (a full hemisphere).
// `environment` (SH of the far field, world space) is needed by the farfield output.
// `cache`: what lies off screen (a panorama of frame `frame`; radiance_cache.h), or null.
// `tiles`: the fill's level per surface (FrameInputs::tiles), or null.
AoFrame compute_ao_frame(const GBuffer& g, const Camera& cam, const Params& p,
                         const SH9* environment = nullptr, const RadianceCache* cache = nullptr,
                         int frame = 0, const FillTiles* tiles = nullptr);

// The two halves of compute_ao_frame, for the temporal chain (temporal.h), which blends the
// search's result with its history in between. `p` has its outputs resolved
// (resolve_frame_outputs).
struct FrameInputs {
  bool rotate = false;  // turn the slices and shift the step jitter by the frame number
  int frame = 0;
  // E/π per pixel added to DiffDir in the source radiance of the first bounce (the previous
  // frame's indirect light, reprojected), or empty. search_frame releases it once used.
  std::vector<Vec3> feedback;
  // What earlier frames showed off screen (radiance_cache.h), or null: the gather's empty
  // directions see unseen_radiance alone.
  const RadianceCache* cache = nullptr;
  // A record of this frame's gather (interleave.h, GatherRecord), or null: an empty one is
  // filled by the first bounce, a filled one is summed instead of marching. Only for searches
  // of the same view with the same parameters but for unseen_scale, the feedback and the
  // bounce (calibration.cpp solves the fill's level with it); the bitmask method, interleaved.
  GatherRecord* record = nullptr;
  // A calibrated fill level per surface (fill_tiles.h), or null: each searched pixel's fill
  // is multiplied by its factor at the pixel's world position.
  const FillTiles* tiles = nullptr;
  // A reduced search (search_scale f > 1) for a caller that works on its texels (the temporal
  // chain): the last bounce is returned on the texels of reduce_view(v, f), neither upsampled
  // nor weighted by diffuse_weight (the caller does both once it has blended them). Earlier
  // bounces are upsampled and weighted as always, since their irradiance lights the next.
  bool keep_reduced = false;
  // reduce_view(v, f) and plan_upsample(v, *reduced, f, depth_tolerance) when the caller has
  // them (null: made here).
  const ViewGBuffer* reduced = nullptr;
  const UpsamplePlan* plan = nullptr;
};
Params resolve_frame_outputs(const GBuffer& g, const Params& requested);
// unseen_radiance "auto" = auto_unseen_factor(unseen_carry) x the mean over the frame's
// geometry pixels of its direct outgoing radiance, DiffCol x DiffDir + Emit, times, per
// pixel, what does not escape over its hemisphere (unseen.h). The factor is the fill's level:
//  - with unseen_carry, 0.8, chosen on samples/room_poles (the best of 0.3-1.5 for the
//    composite against the 8-bounce render over its camera move);
//  - with an escape pass (GBuffer::escape, which says which directions a surface blocks, so
//    that only those get the fill), 0.8 as well: of 0.6, 0.8, 1.0 and 1.2, the largest that
//    lowers the composite of none of the ten scenes of the README's unseen table (1.0 gains
//    0.35-1.46 dB more on eight of them and loses 2.0-2.5 dB on the other two);
//  - where the elevations the frame does not show escape (the default), 1.2: fewer
//    directions get the fill there, and each needs more of it. Of 0.8, 1.2 and 1.6, the
//    largest that lowers the composite of no scene of the README's unseen table but the
//    table top in its void, chosen on those nine scenes and checked on two rendered after
//    the choice (README, "Light from what the frame does not show").
constexpr float kAutoUnseenCarry = 0.8f;
constexpr float kAutoUnseenEscape = 1.2f;
constexpr float auto_unseen_factor(bool unseen_carry) {
  return unseen_carry ? kAutoUnseenCarry : kAutoUnseenEscape;
}
// The mean over v's geometry pixels of g's DiffCol x DiffDir + Emit, per channel; the same
// for any thread count.
Vec3 mean_direct_radiance(const ViewGBuffer& v, const GBuffer& g);
// Whether the outputs need the irradiance gather (irradiance, indirect, composite).
bool gathers(const Params& p);
HorizonImage search_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam,
                          const Params& p, FrameInputs in);
// ao, cone and bent from h.ao, h.vis, h.bent (view space), and the colour outputs from
// h.irradiance. The outputs take over h's buffers (pass it with std::move where it is not
// needed after), so that a frame's search result and outputs are not both in memory.
// `release` (g itself, or null): the composite is made in place over g's DiffDir and takes
// over its alpha, and the fields only it reads (Emit, Env, the glossy and transmission
// passes) are freed once it is made.
AoFrame assemble_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam, const Params& p,
                       HorizonImage h, const SH9* environment, GBuffer* release = nullptr);

// The same from an already prepared view-space G-buffer (used by tests and benchmarks).
// `g` supplies the world normals and, for irradiance, the colour fields.
AoFrame compute_ao_frame(const ViewGBuffer& v, const GBuffer& g, const Camera& cam, const Params& p,
                         const SH9* environment = nullptr, const RadianceCache* cache = nullptr,
                         int frame = 0, const FillTiles* tiles = nullptr);

}  // namespace hbil
