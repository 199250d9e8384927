// radiance_cache.h: light from surfaces earlier frames showed and this one does not.
//
// Screen space finds no surface in the directions that leave the frame, and the gather lights
// them with unseen_radiance (HorizonConfig::fill; "auto" by default, unseen.h). Over a camera move
// the surfaces there were often on screen a few frames before: a pan away from a lit wall still
// receives its light. The cache keeps what the frames of a run showed, in world space, and
// gives each pixel of a later frame the radiance of its off-screen directions (HBIL §4's
// "off-screen buffer", kept in world space instead of a paraboloid of the current view).
//
// What it holds (RadianceCache::add, once a frame's outputs are known): on a regular grid of
// the frame's pixels (1 in s x s, s = ceil(width / kColumns), so about kColumns x
// kColumns·height/width entries a frame at any resolution), each geometry pixel's world
// position and outgoing diffuse radiance DiffCol x (DiffDir + E/π) (+ Emit if emit_gathered) (with
// E the frame's indirect irradiance as output, the temporal chain's accumulated one), and each
// background pixel's world direction (a known empty direction: the sky's light is already
// in DiffDir). Entries older than `frames` frame numbers are dropped, so a frame's fill
// depends on at most the `frames` frames before it, and a farm chunk with that much pre-roll
// computes what the whole run does. Memory: sizeof(Entry) = 32 bytes an entry (32 MB per
// million); at most frames x kColumns x ceil(kColumns·height/width) entries.
//
// What a frame reads from it (RadianceCache::fill_map), before its search:
//  1. The probe: every entry seen from this frame's camera centre, in an equirectangular map
//     of kProbeWidth x kProbeHeight view-space directions. A texel takes the mean radiance of
//     its entries within kDepthBand of its nearest one (a z-buffer that averages the nearest
//     surface's samples); a texel with only background entries is known dark; a texel with
//     none is unknown. Entries inside the camera's frustum, and texels whose centre is, are
//     left out: there the screen itself is searched, and what the search misses there (the
//     space beyond gather_radius, sky seen through the frame) keeps unseen_radiance.
//  2. The fill per normal: for each of kTableWidth x kTableHeight normals n, with cosine
//     weights c_t = max(0, n·d_t) Ω_t over the texels t outside the frustum,
//       F(n) = (Σ c_t L_t [known] + fallback Σ c_t [unknown] + fallback ε) / (Σ c_t + ε),
//     ε = kEpsilon π: the cosine-weighted mean radiance of what lies off screen on the
//     pixel's side, unknown texels taking the fallback (unseen_radiance); a normal that
//     faces no off-screen direction takes the fallback.
//  3. Each geometry pixel of the searched view takes F of its view-space normal (bilinear in
//     the table); background pixels 0. With a fallback per pixel ("auto": each pixel's own
//     fill, unseen.h) F is split into its known part and its unknown share, and each pixel
//     takes the known part plus its own fallback times the unknown share.
// The probe is taken at the camera centre, not at each pixel (a distant-light assumption
// like the far field's), and visibility between pixel and cached surface is not tested: the
// gather only asks in the directions where its own search found nothing.
//
// A panoramic G-buffer of the frame (Params::panorama: Cycles' equirectangular camera at the
// frame's camera position, direct light only) feeds the same probe (set_panorama): its
// geometry pixels with their world position and DiffCol x (DiffDir + A) (+ Emit, as above), A its
// panorama_ambient, for that frame alone. Unlike the frames' entries, its entries and texels
// inside the frustum count too: it knows what lies beyond gather_radius there. Its
// background is left unknown, so it takes the fallback (unseen_radiance; with "auto" each
// pixel's own fill, from the escape pass or the frame's escape profile; 0 leaves the sky dark,
// its light being in DiffDir). Then the first frame
// of a run and single frames have a fill too.
//
// Frames ahead (Params::radiance_cache_ahead, add_ahead): a run can also read the frames that
// follow the one it computes, before their turn (a first pass over the shot, a frame at a
// time, `ahead` frames in advance). Their entries are those of add with E = 0, the frame's
// direct light alone (its indirect light is not computed yet), and frame f reads those of
// frames f + 1 .. f + ahead that no known cut separates from it: a cut given for a frame, or
// found from its camera's jump from the frame before it (temporal.h, camera_cut). A cut that
// only the history's rejection finds is not known ahead. When a frame is computed, add
// replaces its entries ahead with what it output.
//
// With an empty cache (a run's first frame, the frame after a cut, single frames) and on a
// static camera (nothing outside the frustum is known) the fill is the fallback everywhere:
// the results are those without a cache.
#pragma once

#include <cstddef>
#include <vector>

#include "hbil/camera.h"
#include "hbil/gbuffer.h"

namespace hbil {

class RadianceCache {
 public:
  static constexpr int kColumns = 128;
  static constexpr int kProbeWidth = 64, kProbeHeight = 32;
  static constexpr int kTableWidth = 32, kTableHeight = 16;
  static constexpr float kDepthBand = 0.1f;  // relative to the texel's nearest entry
  static constexpr float kEpsilon = 0.05f;

  struct Entry {
    Vec3 p;  // world position, or the world direction of a background pixel (sky)
    Vec3 L;  // outgoing radiance (0 for sky)
    int frame;
    bool sky;
  };

  // Entries from at most `frames` frame numbers before the one read (0: none), and from at
  // most `ahead` after it (add_ahead).
  explicit RadianceCache(int frames, int ahead = 0) : frames_(frames), ahead_frames_(ahead) {}

  // Frame `frame`'s view-space G-buffer `v` with camera `cam`: its pixels' outgoing radiance
  // g.DiffCol x (g.DiffDir + E[i]) (+ g.Emit, as above), with E the frame's irradiance / π (size
  // v.pixels()). Frames are added in increasing order; entries that no later frame can read
  // are dropped.
  void add(const ViewGBuffer& v, const Camera& cam, const GBuffer& g, const std::vector<Vec3>& E,
           int frame);
  // Frame `frame` seen ahead of its turn: add's entries with E = 0, read by the `ahead`
  // frames before it (see above). `cut`: a cut at `frame`, so that no frame before it reads
  // it or any frame after it. Frames are added in increasing order.
  void add_ahead(const ViewGBuffer& v, const Camera& cam, const GBuffer& g, int frame, bool cut);
  // Drops the earlier frames' entries (a cut); the frames ahead and the panorama stay.
  void clear() { entries_.clear(); }
  size_t size() const { return entries_.size() + ahead_.size(); }
  // Whether it knows nothing: no frame's entries and no panorama.
  bool empty() const { return entries_.empty() && ahead_.empty() && panorama_.empty(); }

  // Frame `frame`'s panorama (world-space positions, background at depth >= background):
  // its geometry pixels on a grid of about kPanoramaColumns columns, read by that frame
  // only; it replaces the one before. Needs position, depth, diffcol and diffdir.
  static constexpr int kPanoramaColumns = 256;
  void set_panorama(const GBuffer& pano, float background, int frame);
  // The indirect radiance every panorama surface is taken to receive: the panorama's mean
  // outgoing direct radiance over the whole sphere (solid-angle weighted, the background
  // dark), divided by 1 - its mean albedo (at most kMaxAmbientAlbedo): the light of
  // endless bounces in an enclosure that looks like the panorama everywhere (the "ambient
  // term" of progressive radiosity), per channel.
  static constexpr double kMaxAmbientAlbedo = 0.9;
  static Vec3 panorama_ambient(const GBuffer& pano, float background);

  // The fill of frame `frame`'s searched view `v` (possibly reduced: only its normals and
  // background are read) with camera `cam` (the frame's full-resolution camera, for the
  // frustum), from the entries of frames `frame - frames` .. `frame - 1`. `fallback`: the
  // unseen_radiance of unknown directions. Deterministic for any thread count.
  std::vector<Vec3> fill_map(const ViewGBuffer& v, const Camera& cam, int frame,
                             Vec3 fallback) const;
  // The same with a fallback per pixel of v (unseen_radiance "auto": each pixel's own fill,
  // unseen.h, from the escape pass or the frame's escape profile): each pixel takes the
  // table's known part, plus its own fallback times the table's unknown share. With a
  // constant fallback this is fill_map's result, up to rounding; where nothing is known, the
  // fallback itself, to the bit.
  std::vector<Vec3> fill_map(const ViewGBuffer& v, const Camera& cam, int frame,
                             const std::vector<Vec3>& fallback) const;
  // Step 2's table alone (kTableWidth x kTableHeight, rows from n.y = -1 (up) to +1),
  // for tests.
  std::vector<Vec3> fill_table(const Camera& cam, int frame, Vec3 fallback) const;
  // The table's value at view-space unit normal n (bilinear).
  static Vec3 lookup(const std::vector<Vec3>& table, const Vec3& n);

 private:
  // Step 2's sums per normal: the cosine-weighted known radiance (known), the weight of the
  // unknown directions plus kEpsilon π (unknown), and the weight of all plus kEpsilon π (all).
  struct Sums {
    std::vector<Vec3d> known;
    std::vector<double> unknown, all;
  };
  Sums fill_sums(const Camera& cam, int frame) const;
  // Appends frame `frame`'s entries to `to`, with E (null: 0).
  static void append(std::vector<Entry>& to, const ViewGBuffer& v, const Camera& cam,
                     const GBuffer& g, const std::vector<Vec3>* E, int frame);
  // Whether frame `frame` reads the entries ahead of frame `ahead`.
  bool reads_ahead(int frame, int ahead) const;

  int frames_, ahead_frames_;
  // The frames' entries, earlier ones and those ahead (each in frame order), and the panorama's.
  std::vector<Entry> entries_, ahead_, panorama_;
  std::vector<int> cuts_;  // the cuts known ahead, in order
};

}  // namespace hbil
