// params_options.cpp: --preset and --set.
#include "cli/commands.h"
#include "hbil/error.h"
#include "io/preset_file.h"

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
                   ->default_str(d.slices_auto ? "auto" : std::to_string(d.slices));
  steps_opt = app.add_option("--steps", steps, "same as --set steps=N (per side of a slice)")
                  ->default_str(std::to_string(d.steps));
}

Params ParamOptions::load() const {
  Params p;
  if (!preset.empty()) p = io::read_preset(preset);
  // The shorthands apply before the --set list, so an explicit --set wins.
  if (radius_opt->count()) p = apply_set(p, "radius=" + nlohmann::json(radius).dump());
  if (slices_opt->count()) p = apply_set(p, "slices=" + std::to_string(slices));
  if (steps_opt->count()) p = apply_set(p, "steps=" + std::to_string(steps));
  for (const auto& s : sets) p = apply_set(p, s);
  return p;
}

}  // namespace hbil::cli
