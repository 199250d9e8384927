// params.h: every tunable of hbil in one struct, with its default, unit and range.
//
// The default of a parameter is stated once, in the member initialiser below; the
// table params_table() adds key, unit, range and meaning and drives the JSON round trip,
// validation, `hbil preset --dump`, the CLI help and the man page. An unknown key or an
// out-of-range value is an Error(Exit::preset) naming the key, the value and the range.
#pragma once

#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

namespace hbil {

struct Params {
  // --- Horizon search (HBIL §1.3, §2.1) ---
  double radius = 1.0;  // world units: occluders farther than this are ignored
  int slices = 2;       // slices per pixel (paper: 2, 90 degrees apart)
  // "auto" (the default): 1 in a temporal chain, whose slices rotate from frame to frame and
  // accumulate, 2 without one (resolve_auto_slices, set by the sequence job; 2 until then).
  // The chain searches a frame without history with 2 (TemporalChain::run).
  bool slices_auto = true;
  // method, thickness, steps and step_power: the lowest mean AO error against the Cycles AO
  // pass over both Blender samples (sweeps in README "Accuracy"): bitmask, 0.4, 16, 1.
  int steps = 16;              // depth samples per side of a slice
  double step_power = 1.0;     // sample spacing: offset_k = radius * ((k + jitter) / steps)^power
  bool interleave = true;      // 4x4 deinterleaved rendering (§3.3); off = every pixel all slices
  bool spatial_filter = true;  // depth-aware 4x4 filter after re-interleaving
  double depth_tolerance = 0.05;  // spatial filter: relative depth difference still averaged
  bool vectorised = true;  // SIMD march and view G-buffer (identical results); false = scalar
  int search_scale = 0;    // the search runs on every n-th pixel of every n-th row (reduced.h);
                           // 0: auto (effective_search_scale: >= 540 pixels across)

  // --- Occlusion model and indirect light ---
  std::string method = "bitmask";  // "horizon" (HBIL) or "bitmask" (Therrien et al. 2023)
  double thickness = 0.4;          // bitmask: occluder thickness behind each sample, world units
  // thickness "auto" (the default): derived per shot from the first frame (scene_scale.h);
  // until it is resolved, the number above applies.
  bool thickness_auto = true;
  // bitmask: the thickness of the gather-only samples (between radius and gather_radius);
  // "auto" (the default): kAutoThickness x the median depth where thickness is auto too,
  // else thickness.
  double gather_thickness = 0.4;
  bool gather_thickness_auto = true;
  double thickness_growth = 0.0;  // bitmask: extra thickness per world unit of sample depth
  // bitmask, frames without a back-face layer: each pixel's thickness is the
  // world extent of its surface on screen, up to thickness (thickness_from_extent, gbuffer.h).
  bool thickness_extent = true;
  int bounces = 1;  // in-frame bounces of indirect light (1 = one bounce)
  // gather_steps: the best indirect error against the samples' 1-bounce Cycles references
  // (README "Indirect light"): 16 more samples per side.
  double gather_radius = 4.0;  // irradiance gather reach, world units (<= radius: radius)
  // gather_radius "auto" (the default): the frame's width at the median depth, resolved per
  // shot (scene_scale.h); until then the number above applies.
  bool gather_radius_auto = true;
  int gather_steps = 16;  // gather-only samples per side beyond radius
  // Radiance of the directions where the gather finds no surface (nothing within
  // gather_radius, or the screen edge first); "auto": auto_unseen_factor x the frame's mean direct
  // outgoing radiance (ao_frame.h), times what does not escape over each pixel's hemisphere
  // (unseen.h).
  double unseen_radiance = 0.0;
  bool unseen_radiance_auto = true;
  // unseen_radiance "auto": the elevations the frame does not reach escape (false), or are as
  // open as the nearest one it does (true: enclosed shots, presets/interior.json). "auto"
  // (unseen_carry_auto): true where a calibration is used (its render sets the fill's level,
  // the frame's edges its shape), false otherwise; resolved by the sequence job.
  bool unseen_carry = false;
  bool unseen_carry_auto = true;
  // unseen_radiance (auto or a number) is multiplied by this: the fill's level. With
  // `calibration`, the factor is solved per calibration frame instead (pipeline/calibration.h).
  double unseen_scale = 1.0;
  // A frame pattern (or one file) of renders with global illumination, at any sample count and
  // resolution, of some of the shot's frames (DiffCol and DiffInd): at each, unseen_scale is
  // the factor that gives hbil's single-frame indirect light the render's mean; "auto": the
  // input's file names in a folder calibration/ beside its frames, where any exists
  // (pipeline/calibration.h, resolve_calibration); "" (off).
  std::string calibration = "auto";
  // With `calibration`: the columns of a grid of tiles over each calibration frame, in each of
  // which the fill's level is solved as well (rows in proportion, at most one tile per 256 of the
  // render's pixels), relative to the frame's factor; the factor of a surface is its tile's,
  // bilinear between tile centres, where a calibration frame sees it (pipeline/calibration.h,
  // hbil/fill_tiles.h). 0: one factor per calibration frame.
  int calibration_tiles = 8;
  std::string environment;  // far field: "" (off), equirect EXR path, or "rgb:r,g,b"
  // A frame pattern of panoramic G-buffers from each frame's camera position (Position,
  // DiffCol, DiffDir, Emit, Depth), whose off-screen part lights the gather's empty
  // directions (radiance_cache.h); "" (off).
  std::string panorama;
  // Whether the gather takes the Emit pass as light: "direct" (the renderer's DiffDir already
  // holds the light emitting surfaces cast, as Cycles' does), "gathered" (it does not: a
  // POV-Ray import, whose emitters light the scene through radiosity only), "auto" (gathered
  // for a frame `hbil import-povray` wrote, else direct). Emit enters the composite either way.
  std::string emission = "auto";
  bool ao_multibounce = false;  // ao as RGB with the multi-bounce fit (improved-AO eq. 12)

  // --- Temporal chain (HBIL §2.3.1 eq. 17, §3.2, §3.3): across the frames of one run ---
  bool temporal = true;  // reprojection, radiance feedback, accumulation, rotation
  std::string reprojection =
      "auto";                   // "auto" (vector when present, else scatter), "scatter", "vector"
  bool feedback = true;         // gather last frame's indirect light too (a bounce per frame)
  bool push_pull = true;        // fill disocclusions of the feedback from their surroundings
  double history_weight = 0.9;  // exponential blend: weight of the history once converged
  int history_max = 16;         // history length cap (frames); 1/n blend until then
  int history_window = 0;       // > 0: finite memory, two staggered plain means (temporal.h)
  // > 0: the off-screen directions see what the last this many frames showed there
  // (radiance_cache.h); 0: unseen_radiance only.
  int radiance_cache = 0;
  // > 0: and what the next this many frames show, read ahead of their turn with their direct
  // light (radiance_cache.h, add_ahead); 0: off.
  int radiance_cache_ahead = 0;
  double history_depth_tolerance = 0.05;  // relative depth mismatch that rejects history
  double history_normal_cos = 0.8;        // cosine between normals below which history is rejected
  double cut_rejected = 0.6;     // a frame whose history is rejected on more pixels is a cut
  double cut_camera_jump = 0.5;  // camera move / median depth beyond which a frame is a cut
  double cut_camera_angle = 45;  // camera rotation (degrees) beyond which a frame is a cut

  // --- Input ---
  double background_depth = 1e9;  // depth >= this (Blender: 1e10) is background
  std::string view_layer;         // "" = detect (the layer holding Depth or Normal)
  std::string input_space;        // OCIO colour space of the colour passes; "" = scene_linear
  // G-buffer field -> channels. A string names a pass ("Normal" -> <layer>.Normal.X/Y/Z),
  // or a full channel prefix containing a dot; an array lists exact channel names.
  std::map<std::string, nlohmann::json> passes = default_passes();

  // --- Output ---
  // "auto": ao, bentcone, and irradiance, indirect and composite when the input has the
  // colour passes they need (see resolve_outputs); may be combined with explicit names.
  std::vector<std::string> outputs = {"auto"};
  // EXR compression of the output frames: "zip", "zips", "piz", "rle", "dwaa" (lossy on
  // channels ending in R, G, B or Y, so on data layers too), "none".
  std::string compression = "rle";
  bool colour_half = true;  // colour layers as half floats (data layers stay 32-bit float)

  static std::map<std::string, nlohmann::json> default_passes();
  // Number of slice directions one pixel's result integrates (after re-interleaving).
  int slice_directions() const { return interleave ? 16 * slices : slices; }
  bool wants(const std::string& output) const;
};

// slices "auto" resolved for a run that has (chain) or has not a temporal chain: 1 or 2;
// p unchanged where slices is a number.
inline Params resolve_auto_slices(Params p, bool chain) {
  if (p.slices_auto) p.slices = chain ? 1 : 2;
  return p;
}

// One row of the parameter table: the key, what it means, its unit and its range.
struct ParamInfo {
  const char* key;
  std::variant<double Params::*, int Params::*, bool Params::*> member;
  double min, max;  // inclusive; unused for bool
  const char* unit;
  const char* help;
};
const std::vector<ParamInfo>& params_table();

// The G-buffer fields a preset may map, and the outputs hbil can write.
const std::vector<std::string>& gbuffer_fields();
const std::vector<std::string>& known_outputs();
// The values of the key compression.
const std::vector<std::string>& output_compressions();

// The outputs "auto" stands for, in order.
const std::vector<std::string>& auto_outputs();
// `p` with "auto" replaced by the auto_outputs() for which available(output) holds (those
// already named explicitly are not repeated); the others are appended to `dropped`.
Params resolve_outputs(const Params& p, const std::function<bool(const std::string&)>& available,
                       std::vector<std::string>* dropped = nullptr);

nlohmann::json to_json(const Params& p);
// Starts from `base` and applies the keys in j; `where` names the source in errors
// (a file name, "--set"). Throws Error(Exit::preset).
Params params_from_json(const nlohmann::json& j, const std::string& where, Params base = {});
// Applies "key=value" (value parsed as JSON, else taken as a string; dotted keys reach
// into objects: passes.depth=Depth). Throws Error(Exit::preset).
Params apply_set(const Params& p, const std::string& assignment);
// Checks ranges and consistency. Throws Error(Exit::preset).
void validate(const Params& p, const std::string& where);

}  // namespace hbil
