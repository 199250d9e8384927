// params.cpp: the parameter table, JSON round trip and validation.
#include "hbil/params.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hbil/error.h"

namespace hbil {

using nlohmann::json;

std::map<std::string, json> Params::default_passes() {
  return {{"depth", "Depth"},
          {"normal", "Normal"},
          {"position", "Position"},
          {"alpha", "Combined.A"},
          {"diffcol", "DiffCol"},
          {"diffdir", "DiffDir"},
          {"emit", "Emit"},
          {"env", "Env"},
          {"glosscol", "GlossCol"},
          {"glossdir", "GlossDir"},
          {"glossind", "GlossInd"},
          {"transcol", "TransCol"},
          {"transdir", "TransDir"},
          {"transind", "TransInd"},
          {"backdepth", "BackFaces.Depth.Z"},
          {"f0", ""},
          {"metallic", ""},
          {"vector", "Vector"},
          {"escape", ""}};
}

bool Params::wants(const std::string& output) const {
  return std::find(outputs.begin(), outputs.end(), output) != outputs.end();
}

const std::vector<ParamInfo>& params_table() {
  static const std::vector<ParamInfo> table = {
      {"radius", &Params::radius, 1e-6, 1e6, "world units",
       "AO radius: occluders farther than this from the shaded point are ignored "
       "(set Cycles' World > Ambient Occlusion > Distance to the same value to compare)"},
      {"slices", &Params::slices, 1, 64, "per pixel",
       "slice directions marched per pixel; with interleave the 4x4 block covers 16x this; "
       "\"auto\" (default): 1 in a temporal chain, whose slices rotate from frame to frame and "
       "accumulate (2 on its first frame and the first after a cut), 2 without one (temporal "
       "false, or a run of one frame)"},
      {"steps", &Params::steps, 1, 256, "per side", "depth samples along each side of a slice"},
      {"step_power", &Params::step_power, 1, 4, "exponent",
       "sample spacing along a slice: offset = radius * ((k + jitter) / steps)^step_power; "
       "values above 1 sample near occluders more densely"},
      {"interleave", &Params::interleave, 0, 1, "bool",
       "4x4 deinterleaved rendering (HBIL 3.3): each pixel marches `slices` directions, "
       "rotated per pixel of the 4x4 block; false marches all directions at every pixel"},
      {"spatial_filter", &Params::spatial_filter, 0, 1, "bool",
       "after re-interleaving, average each pixel with the 4x4 block around it (depth- and "
       "normal-aware) so that every pixel integrates all 16 x slices directions"},
      {"vectorised", &Params::vectorised, 0, 1, "bool",
       "march the pixels of a row in SIMD lanes (AVX-512, AVX2, ... chosen at run time); false "
       "runs the scalar reference, which gives the same results to the bit"},
      {"search_scale", &Params::search_scale, 0, 8, "pixels",
       "the horizon search and gather run on every n-th pixel of every n-th row (1/n^2 of the "
       "cost) and their result is upsampled to every pixel over the same surface (depth- and "
       "normal-aware, like the spatial filter); 1 searches at every pixel; 0 (auto): the "
       "largest n that keeps 540 pixels across the frame's shorter side"},
      {"depth_tolerance", &Params::depth_tolerance, 0, 1, "relative",
       "spatial filter: neighbours farther from the pixel's tangent plane than this fraction of "
       "its depth are not averaged (nor those whose normal is more than 37 degrees off)"},
      {"thickness", &Params::thickness, 0, 1e6, "world units",
       "method bitmask: every depth sample occludes like a slab this thick behind it (HBIL's "
       "horizon is the limit of infinite thickness); with a back-face layer, only where a "
       "pixel has no back face; \"auto\" (default): 0.15 x the first frame's median depth, at "
       "most 0.4 x radius"},
      {"gather_thickness", &Params::gather_thickness, 0, 1e6, "world units",
       "method bitmask: the thickness of the gather-only samples (between radius and "
       "gather_radius), which light and shadow irradiance but not ao; \"auto\" (default): "
       "0.3 x the first frame's median depth where thickness is auto, else thickness"},
      {"thickness_extent", &Params::thickness_extent, 0, 1, "bool",
       "method bitmask, frames without a back-face layer: an object is taken to be as thick as "
       "it is wide, up to thickness: each pixel's thickness is the smaller world extent of its "
       "surface along its row and its column on screen, used as a back-face layer's would be"},
      {"thickness_growth", &Params::thickness_growth, 0, 1e3, "per world unit",
       "method bitmask: thickness added per world unit of the sample's depth"},
      {"gather_radius", &Params::gather_radius, 0, 1e6, "world units",
       "how far the irradiance gather reaches; occluders and emitters between radius and "
       "gather_radius light and shadow irradiance but not ao (values <= radius: radius); "
       "\"auto\" (default): the width of the first frame at its median depth"},
      {"gather_steps", &Params::gather_steps, 0, 256, "per side",
       "samples per side of a slice between radius and gather_radius, seen only by the gather"},
      {"unseen_radiance", &Params::unseen_radiance, 0, 1e6, "radiance",
       "the radiance assumed in the directions where the gather finds no surface: none within "
       "gather_radius, or the screen edge first (light from what the frame does not show); "
       "\"auto\" (default): 1.2 x (0.8 x with unseen_carry) the frame's mean direct outgoing "
       "radiance, DiffCol x DiffDir + Emit over its geometry, times the fraction of each "
       "pixel's hemisphere that the frame's background does not show escaping; 0: none"},
      {"unseen_carry", &Params::unseen_carry, 0, 1, "bool",
       "unseen_radiance \"auto\": the elevations above and below what the frame shows are "
       "taken to be as open as the frame's top and bottom edges say: background, and a floor "
       "at the top edge or a ceiling at the bottom, leave them open, walls close them (true: "
       "for enclosed shots, presets/interior.json); false: they escape, so that a frame says "
       "nothing of what it does not reach; \"auto\" (default): true where a calibration is "
       "used, false otherwise"},
      {"unseen_scale", &Params::unseen_scale, 0, 1e3, "factor",
       "unseen_radiance (auto or a number) is multiplied by this; with calibration, the factor "
       "is solved at each calibration frame instead (and interpolated between them)"},
      {"calibration_tiles", &Params::calibration_tiles, 0, 64, "columns",
       "with calibration: the fill's level is solved in a grid of this many columns of tiles "
       "(rows in proportion, at most one tile per 256 pixels of the render) over each "
       "calibration frame as well, and each surface takes its tile's factor where a "
       "calibration frame sees it; 0: one factor per calibration frame"},
      {"bounces", &Params::bounces, 1, 16, "count",
       "in-frame bounces of indirect light: bounce k gathers the outgoing radiance of bounce k-1"},
      {"ao_multibounce", &Params::ao_multibounce, 0, 1, "bool",
       "write ao as ao.R/G/B with the multi-bounce approximation of the improved-AO notes "
       "(eq. 12, per channel with DiffCol as albedo) instead of ao.Y; needs DiffCol"},
      {"temporal", &Params::temporal, 0, 1, "bool",
       "temporal chain over the frames of a run: reprojection of the previous frame, radiance "
       "feedback, accumulation of irradiance, ao and bentcone, slices rotating with the frame"},
      {"feedback", &Params::feedback, 0, 1, "bool",
       "temporal: the gather's source radiance includes the previous frame's indirect light "
       "(reprojected), so light bounces once more every frame (HBIL eq. 17)"},
      {"push_pull", &Params::push_pull, 0, 1, "bool",
       "temporal: fill disocclusions of the reprojected irradiance from their surroundings "
       "through a depth-aware mip pyramid (push/pull)"},
      {"history_weight", &Params::history_weight, 0, 0.99, "fraction",
       "temporal: weight of the accumulated history against the current frame once its "
       "history is long enough (exponential blend)"},
      {"history_max", &Params::history_max, 1, 1024, "frames",
       "temporal: a pixel with n frames of history blends the current one with weight "
       "max(1/n, 1 - history_weight), n capped here"},
      {"history_window", &Params::history_window, 0, 64, "frames",
       "temporal: 0: the exponential blend of history_weight and history_max; W >= 2: a "
       "memory of at most 2W - 2 frames (two plain means restarted every 2W frames, W apart, "
       "blended so that neither restart shows), so that a farm chunk with 2W - 2 frames of "
       "pre-roll starts as the whole run would"},
      {"radiance_cache", &Params::radiance_cache, 0, 256, "frames",
       "temporal: the gather's empty directions that leave the frame see the surfaces the last "
       "this many frames showed there (a world-space cache of their positions and outgoing "
       "radiance, looked up from the camera); unseen_radiance where none did; 0: off"},
      {"radiance_cache_ahead", &Params::radiance_cache_ahead, 0, 256, "frames",
       "temporal: the same with the surfaces the next this many frames show, read ahead of "
       "their turn with their direct light alone (DiffCol x DiffDir, + Emit where gathered); a "
       "frame does not read those beyond a known cut (given, or a camera jump); 0: off"},
      {"history_depth_tolerance", &Params::history_depth_tolerance, 0, 1, "relative",
       "temporal: history whose reprojected depth differs by more than this fraction is "
       "rejected"},
      {"history_normal_cos", &Params::history_normal_cos, -1, 1, "cosine",
       "temporal: history whose normal is farther than this from the pixel's is rejected"},
      {"cut_rejected", &Params::cut_rejected, 0, 1, "fraction",
       "temporal: a frame that rejects the history of more than this fraction of its pixels "
       "is a camera cut (history dropped)"},
      {"cut_camera_jump", &Params::cut_camera_jump, 0, 1e6, "fraction of median depth",
       "temporal: a camera that moves farther than this times the frame's median depth is a "
       "cut"},
      {"cut_camera_angle", &Params::cut_camera_angle, 0, 180, "degrees",
       "temporal: a camera that turns by more than this is a cut"},
      {"background_depth", &Params::background_depth, 1e-6, 1e30, "world units",
       "depth at or beyond which a pixel is background (Blender writes 1e10)"},
      {"colour_half", &Params::colour_half, 0, 1, "bool",
       "write the colour layers (irradiance, indirect, farfield, composite) as 16-bit half "
       "floats (relative error <= 4.9e-4); ao, bentcone and history stay 32-bit float"},
  };
  return table;
}

const std::vector<std::string>& gbuffer_fields() {
  static const std::vector<std::string> f = {
      "depth",     "normal",   "position", "alpha",    "diffcol",  "diffdir",  "emit",
      "env",       "glosscol", "glossdir", "glossind", "transcol", "transdir", "transind",
      "backdepth", "f0",       "metallic", "vector",   "escape"};
  return f;
}

const std::vector<std::string>& known_outputs() {
  static const std::vector<std::string> o = {"ao",       "bentcone",  "irradiance", "indirect",
                                             "farfield", "composite", "history"};
  return o;
}

const std::vector<std::string>& output_compressions() {
  static const std::vector<std::string> c = {"zip", "zips", "piz", "dwaa", "rle", "none"};
  return c;
}

const std::vector<std::string>& auto_outputs() {
  static const std::vector<std::string> o = {"ao", "bentcone", "irradiance", "indirect",
                                             "composite"};
  return o;
}

Params resolve_outputs(const Params& p, const std::function<bool(const std::string&)>& available,
                       std::vector<std::string>* dropped) {
  if (!p.wants("auto")) return p;
  Params r = p;
  r.outputs.clear();
  for (const std::string& o : p.outputs) {
    if (o != "auto") {
      if (!r.wants(o)) r.outputs.push_back(o);
      continue;
    }
    for (const std::string& a : auto_outputs()) {
      if (p.wants(a) || r.wants(a)) continue;
      if (available(a))
        r.outputs.push_back(a);
      else if (dropped)
        dropped->push_back(a);
    }
  }
  return r;
}

json to_json(const Params& p) {
  json j;
  for (const ParamInfo& info : params_table()) {
    std::visit([&](auto m) { j[info.key] = p.*m; }, info.member);
  }
  if (p.slices_auto) j["slices"] = "auto";
  if (p.gather_radius_auto) j["gather_radius"] = "auto";
  if (p.thickness_auto) j["thickness"] = "auto";
  if (p.gather_thickness_auto) j["gather_thickness"] = "auto";
  if (p.unseen_radiance_auto) j["unseen_radiance"] = "auto";
  if (p.unseen_carry_auto) j["unseen_carry"] = "auto";
  j["method"] = p.method;
  j["reprojection"] = p.reprojection;
  j["emission"] = p.emission;
  j["environment"] = p.environment;
  j["panorama"] = p.panorama;
  j["calibration"] = p.calibration;
  j["view_layer"] = p.view_layer;
  j["input_space"] = p.input_space;
  j["passes"] = p.passes;
  j["outputs"] = p.outputs;
  j["compression"] = p.compression;
  return j;
}

namespace {

std::string allowed_list(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

[[noreturn]] void fail(const std::string& where, const std::string& msg) {
  throw Error(Exit::preset, where + ": " + msg);
}

void read_number(Params& p, const ParamInfo& info, const json& v, const std::string& where) {
  std::visit(
      [&](auto m) {
        using T = std::remove_reference_t<decltype(p.*m)>;
        if constexpr (std::is_same_v<T, bool>) {
          if (!v.is_boolean())
            fail(where,
                 std::string("key '") + info.key + "' must be true or false, got " + v.dump());
          p.*m = v.get<bool>();
        } else if constexpr (std::is_same_v<T, int>) {
          if (!v.is_number_integer())
            fail(where, std::string("key '") + info.key + "' must be an integer, got " + v.dump());
          p.*m = v.get<int>();
        } else {
          if (!v.is_number())
            fail(where, std::string("key '") + info.key + "' must be a number, got " + v.dump());
          p.*m = v.get<double>();
        }
      },
      info.member);
}

}  // namespace

Params params_from_json(const json& j, const std::string& where, Params p) {
  if (!j.is_object()) fail(where, "a preset must be a JSON object, got " + j.dump());
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    const json& v = it.value();
    auto row = std::find_if(params_table().begin(), params_table().end(),
                            [&](const ParamInfo& i) { return key == i.key; });
    // gather_radius and thickness: a number, or "auto" (derived from the shot).
    const bool may_be_auto = key == "gather_radius" || key == "thickness" ||
                             key == "gather_thickness" || key == "unseen_radiance" ||
                             key == "slices" || key == "unseen_carry";
    bool& auto_flag = key == "gather_radius"     ? p.gather_radius_auto
                      : key == "thickness"       ? p.thickness_auto
                      : key == "unseen_radiance" ? p.unseen_radiance_auto
                      : key == "slices"          ? p.slices_auto
                      : key == "unseen_carry"    ? p.unseen_carry_auto
                                                 : p.gather_thickness_auto;
    const bool boolean = key == "unseen_carry";
    const std::string number_or_auto = "key '" + key + "' must be " +
                                       (key == "slices" ? "an integer"
                                        : boolean       ? "true, false"
                                                        : "a number") +
                                       " or \"auto\", got ";
    if (may_be_auto && v.is_string()) {
      if (v.get<std::string>() != "auto") fail(where, number_or_auto + v.dump());
      auto_flag = true;
    } else if (row != params_table().end()) {
      if (may_be_auto && !(boolean ? v.is_boolean() : v.is_number()))
        fail(where, number_or_auto + v.dump());
      read_number(p, *row, v, where);
      if (may_be_auto) auto_flag = false;
    } else if (key == "method") {
      if (!v.is_string())
        fail(where, "key 'method' must be \"horizon\" or \"bitmask\", got " + v.dump());
      p.method = v.get<std::string>();
    } else if (key == "reprojection") {
      if (!v.is_string())
        fail(where,
             "key 'reprojection' must be \"auto\", \"scatter\" or \"vector\", got " + v.dump());
      p.reprojection = v.get<std::string>();
    } else if (key == "emission") {
      if (!v.is_string())
        fail(where, "key 'emission' must be \"auto\", \"direct\" or \"gathered\", got " + v.dump());
      p.emission = v.get<std::string>();
    } else if (key == "environment") {
      if (!v.is_string())
        fail(where, "key 'environment' must be a file name or \"rgb:r,g,b\", got " + v.dump());
      p.environment = v.get<std::string>();
    } else if (key == "panorama") {
      if (!v.is_string())
        fail(where, "key 'panorama' must be a frame pattern of EXR files, got " + v.dump());
      p.panorama = v.get<std::string>();
    } else if (key == "calibration") {
      if (!v.is_string())
        fail(where,
             "key 'calibration' must be a frame pattern of EXR files, \"auto\" or \"\", got " +
                 v.dump());
      p.calibration = v.get<std::string>();
    } else if (key == "view_layer") {
      if (!v.is_string()) fail(where, "key 'view_layer' must be a string, got " + v.dump());
      p.view_layer = v.get<std::string>();
    } else if (key == "input_space") {
      if (!v.is_string())
        fail(where, "key 'input_space' must be an OpenColorIO colour space, got " + v.dump());
      p.input_space = v.get<std::string>();
    } else if (key == "passes") {
      if (!v.is_object()) fail(where, "key 'passes' must be an object, got " + v.dump());
      for (auto pit = v.begin(); pit != v.end(); ++pit) {
        const auto& fields = gbuffer_fields();
        if (std::find(fields.begin(), fields.end(), pit.key()) == fields.end())
          fail(where, "unknown G-buffer field 'passes." + pit.key() +
                          "' (known: " + allowed_list(fields) + ")");
        const json& c = pit.value();
        bool ok = c.is_string() ||
                  (c.is_array() && !c.empty() &&
                   std::all_of(c.begin(), c.end(), [](const json& e) { return e.is_string(); }));
        if (!ok)
          fail(where, "key 'passes." + pit.key() +
                          "' must be a pass name or an array of channel names, got " + c.dump());
        p.passes[pit.key()] = c;
      }
    } else if (key == "tuned") {
      // What `hbil tune` tuned the preset on: a record for the reader, not a parameter.
    } else if (key == "compression") {
      if (!v.is_string())
        fail(where, "key 'compression' must be one of " + allowed_list(output_compressions()) +
                        ", got " + v.dump());
      p.compression = v.get<std::string>();
    } else if (key == "outputs") {
      if (!v.is_array())
        fail(where, "key 'outputs' must be an array of layer names, got " + v.dump());
      p.outputs.clear();
      for (const json& o : v) {
        if (!o.is_string()) fail(where, "key 'outputs' must hold strings, got " + o.dump());
        p.outputs.push_back(o.get<std::string>());
      }
    } else {
      std::vector<std::string> keys;
      for (const auto& i : params_table()) keys.push_back(i.key);
      keys.insert(keys.end(),
                  {"method", "reprojection", "emission", "environment", "panorama", "calibration",
                   "view_layer", "input_space", "passes", "outputs", "compression", "tuned"});
      fail(where, "unknown key '" + key + "' (known: " + allowed_list(keys) + ")");
    }
  }
  validate(p, where);
  return p;
}

void validate(const Params& p, const std::string& where) {
  for (const ParamInfo& info : params_table()) {
    std::visit(
        [&](auto m) {
          using T = std::remove_reference_t<decltype(p.*m)>;
          if constexpr (!std::is_same_v<T, bool>) {
            double v = double(p.*m);
            if (!(v >= info.min && v <= info.max)) {
              std::ostringstream s;
              s << "key '" << info.key << "' = " << v << " is out of range [" << info.min << ", "
                << info.max << "] (" << info.unit << ")";
              fail(where, s.str());
            }
          }
        },
        info.member);
  }
  if (p.history_window == 1)
    fail(where, "key 'history_window' = 1: it is 0 (exponential blend) or at least 2");
  if (p.method != "horizon" && p.method != "bitmask")
    fail(where, "key 'method' = \"" + p.method + "\" is not one of \"horizon\", \"bitmask\"");
  if (p.reprojection != "auto" && p.reprojection != "scatter" && p.reprojection != "vector")
    fail(where, "key 'reprojection' = \"" + p.reprojection +
                    "\" is not one of \"auto\", \"scatter\", \"vector\"");
  if (p.emission != "auto" && p.emission != "direct" && p.emission != "gathered")
    fail(where, "key 'emission' = \"" + p.emission +
                    "\" is not one of \"auto\", \"direct\", \"gathered\"");
  if (p.outputs.empty()) fail(where, "key 'outputs' is empty: nothing to compute");
  const auto& comp = output_compressions();
  if (std::find(comp.begin(), comp.end(), p.compression) == comp.end())
    fail(where,
         "key 'compression' = \"" + p.compression + "\" is not one of " + allowed_list(comp));
  if (p.wants("farfield") && p.environment.empty())
    fail(where,
         "output 'farfield' needs key 'environment' (an equirectangular EXR or \"rgb:r,g,b\")");
  for (const auto& o : p.outputs) {
    const auto& k = known_outputs();
    if (o != "auto" && std::find(k.begin(), k.end(), o) == k.end())
      fail(where, "unknown output '" + o + "' in 'outputs' (known: auto, " + allowed_list(k) + ")");
  }
}

Params apply_set(const Params& p, const std::string& assignment) {
  const std::string where = "--set " + assignment;
  auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) fail(where, "expected key=value");
  // Bare words become JSON strings, which must be UTF-8 (hbil writes its parameters into
  // every output as JSON).
  try {
    (void)json(assignment).dump();
  } catch (const json::type_error&) {
    fail(where, "not valid UTF-8 text");
  }
  std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  json value = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) value = text;  // bare words are strings: passes.depth=Depth
  // A dotted key reaches into an object: "passes.depth" -> {"passes": {"depth": value}}.
  // No key is deeper than that.
  if (std::count(key.begin(), key.end(), '.') > 1)
    fail(where, "unknown key '" + key + "' (a key has at most one dot, as in passes.depth)");
  json patch = value;
  for (size_t dot = key.rfind('.'); dot != std::string::npos; dot = key.rfind('.')) {
    patch = json{{key.substr(dot + 1), patch}};
    key = key.substr(0, dot);
  }
  return params_from_json(json{{key, patch}}, where, p);
}

}  // namespace hbil
