// params_options.cpp: --preset and --set.
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cli/commands.h"
#include "hbil/error.h"

namespace hbil::cli {

void ParamOptions::add_to(CLI::App& app) {
  app.add_option("--preset", preset,
                 "JSON preset file (see presets/); keys not in it keep their defaults");
  app.add_option("--set", sets,
                 "override one parameter: key=value, value as JSON (radius=0.5, interleave=false, "
                 "passes.depth=Depth); repeatable, applied after --preset")
      ->allow_extra_args(false);
  const Params d;
  radius_opt = app.add_option("--radius", radius, "same as --set radius=R (world units)")
                   ->default_str(CLI::detail::to_string(d.radius));
  slices_opt = app.add_option("--slices", slices, "same as --set slices=N (per pixel)")
                   ->default_str(std::to_string(d.slices));
  steps_opt = app.add_option("--steps", steps, "same as --set steps=N (per side of a slice)")
                  ->default_str(std::to_string(d.steps));
}

Params read_preset(const std::string& path) {
  // Missing or unreadable is a preset error (exit 7) like a malformed one, named by path.
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw Error(Exit::preset, "--preset " + path + ": file not found");
  if (std::filesystem::is_directory(path, ec))
    throw Error(Exit::preset, "--preset " + path + ": is a folder, not a JSON file");
  std::ifstream in(path);
  if (!in) throw Error(Exit::preset, "--preset " + path + ": cannot read: " + std::strerror(errno));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(Exit::preset, path + ": not valid JSON: " + e.what());
  }
  return params_from_json(j, path);
}

Params ParamOptions::load() const {
  Params p;
  if (!preset.empty()) p = read_preset(preset);
  // The shorthands apply before the --set list, so an explicit --set wins.
  if (radius_opt->count()) p = apply_set(p, "radius=" + nlohmann::json(radius).dump());
  if (slices_opt->count()) p = apply_set(p, "slices=" + std::to_string(slices));
  if (steps_opt->count()) p = apply_set(p, "steps=" + std::to_string(steps));
  for (const auto& s : sets) p = apply_set(p, s);
  return p;
}

}  // namespace hbil::cli
