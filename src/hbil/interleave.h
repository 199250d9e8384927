// interleave.h: running the horizon search over a whole frame, with or without the 4x4
// interleaved rendering of HBIL §3.3 (Bavoil & Jansen 2013, "deinterleaved texturing").
//
// Interleaved: the view-space G-buffer is split into 16 quarter-resolution sub-buffers, one
// per position (ox, oy) in the 4x4 block; each sub-buffer marches `slices` directions (the
// paper: 2, 90° apart) rotated by its own offset, so the 16 pixels of a block together cover
// 16 * slices evenly spaced directions over [0, π). Samples are taken within the sub-buffer
// (every 4th pixel, which is what makes it cache-friendly); results are written back to
// their full-resolution pixels (re-interleaving). The spatial filter then averages each
// block (spatial_filter.h).
// Not interleaved (reference runs): every pixel marches all `slices` directions at full
// resolution, evenly spaced, with no rotation or jitter.
#pragma once

#include <vector>

#include "hbil/gbuffer.h"
#include "hbil/horizon.h"
#include "hbil/march.h"

namespace hbil {

// Per-pixel horizon results before the spatial filter: means over the pixel's slices.
struct HorizonImage {
  int width = 0, height = 0;
  std::vector<float> ao;         // cosine-weighted visibility (eq. 9), 1 = unoccluded
  std::vector<float> vis;        // uniform visibility Ω / 2π
  std::vector<Vec3> bent;        // mean slice bent vector, view space, not normalised
  std::vector<Vec3> irradiance;  // E_near / π (eq. 16-18); empty without a radiance source
  // ao, vis and bent empty: the irradiance alone (a later in-frame bounce, whose occlusion is
  // the first's), which the spatial filter and the upsample carry as such.
  bool irradiance_only() const { return ao.empty() && !irradiance.empty(); }
};

// The result of a search that found nothing: ao = vis = 1, bent = 0 (and irradiance = 0 when
// `gather`), at g's size; what background pixels keep.
HorizonImage unoccluded_image(const ViewGBuffer& g, bool gather);

// A weighted mean of search results (the spatial filter's and the upsample's): add() texel k
// of an image with weight w, then store() the mean into pixel p.
struct HorizonMean {
  float ao = 0, vis = 0, w = 0;
  Vec3 bent, irradiance;
  void add(const HorizonImage& h, size_t k, float wk) {
    if (!h.ao.empty()) {
      ao += wk * h.ao[k];
      vis += wk * h.vis[k];
      bent += h.bent[k] * wk;
    }
    if (!h.irradiance.empty()) irradiance += h.irradiance[k] * wk;
    w += wk;
  }
  // w > 0.
  void store(HorizonImage& out, size_t p) const {
    const float inv = 1.f / w;  // one division, not eight
    if (!out.ao.empty()) {
      out.ao[p] = ao * inv;
      out.vis[p] = vis * inv;
      out.bent[p] = bent * inv;
    }
    if (!out.irradiance.empty()) out.irradiance[p] = irradiance * inv;
  }
};

// Slice angles and step jitter of one of the 16 pixels of the 4x4 block
// (phase = (y % 4) * 4 + x % 4).
void interleaved_angles(int phase, int slices, float* phi);
float interleaved_jitter(int phase);

// Every pixel, all slices, full resolution (Params::interleave = false).
// `radiance` (one L_d per pixel, or null) is gathered into HorizonImage::irradiance.
HorizonImage horizon_full(const ViewGBuffer& g, const HorizonConfig& c, int slices,
                          const std::vector<Vec3>* radiance = nullptr);

// What an interleaved bitmask search gathered (march.h, GatherLog: one log per sub-buffer row),
// and its result, so that the later in-frame bounces of the same frame sum their light
// without marching again (the geometry, so occlusion and every weight, is the same).
struct GatherRecord {
  bool filled = false;
  std::vector<GatherLog> rows;  // per (phase, row) of the search
  HorizonImage first;           // the recorded search's result (before the spatial filter)
};

// The 4x4 interleaved search. With copy_subbuffers = false the sub-buffers are read in place
// through strided views (the plain version the tests compare the copying one against).
// `record` (bitmask method with a radiance source; else ignored): when empty, the search
// fills it; when filled, nothing is marched: ao, vis and bent are the recorded ones and the
// irradiance is the recorded gather summed with `radiance`, identical to a new search.
// `irradiance_only`: the result holds the irradiance alone (HorizonImage::irradiance_only; a
// later bounce, whose occlusion is the first's), not copied from the record on a replay.
HorizonImage horizon_interleaved(const ViewGBuffer& g, const HorizonConfig& c, int slices,
                                 const std::vector<Vec3>* radiance = nullptr,
                                 bool copy_subbuffers = true, GatherRecord* record = nullptr,
                                 bool irradiance_only = false);

}  // namespace hbil
