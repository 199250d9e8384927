// preset.cpp: `hbil preset --dump` prints the effective parameters; `--describe` the table.
#include <iomanip>
#include <iostream>

#include "cli/commands.h"
#include "hbil/error.h"

namespace hbil::cli {

void add_preset(CLI::App& app) {
  struct Options {
    bool dump = false, describe = false;
    ParamOptions params;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd =
      app.add_subcommand("preset", "print the effective parameters or describe every key");
  cmd->add_flag("--dump", o->dump,
                "print the effective parameters (defaults, --preset, --set) as JSON");
  cmd->add_flag("--describe", o->describe,
                "list every key with its default, range, unit and meaning");
  o->params.add_to(*cmd);
  cmd->callback([o] {
    if (!o->dump && !o->describe) throw Error(Exit::usage, "preset: give --dump or --describe");
    if (o->dump) std::cout << to_json(o->params.load()).dump(2) << "\n";
    if (o->describe) {
      const nlohmann::json d = to_json(Params{});
      for (const ParamInfo& i : params_table()) {
        std::cout << i.key << " = " << d[i.key].dump();
        if (!std::holds_alternative<bool Params::*>(i.member))
          std::cout << "  [" << i.min << ", " << i.max << "]";
        std::cout << "  (" << i.unit << ")\n    " << i.help << "\n";
      }
      std::cout
          << "method = " << d["method"].dump()
          << "\n    occlusion model: \"horizon\" (HBIL) or \"bitmask\" (visibility bitmask)\n";
      std::cout << "environment = " << d["environment"].dump()
                << "\n    far field: \"\" (off), an equirectangular EXR, or \"rgb:r,g,b\"\n";
      std::cout << "panorama = " << d["panorama"].dump()
                << "\n    a frame pattern of panoramic G-buffers of each frame (light from what "
                   "the frame does not show); \"\" (off)\n";
      std::cout << "calibration = " << d["calibration"].dump()
                << "\n    a frame pattern of 1-spp renders with global illumination of some "
                   "frames (DiffCol, DiffInd), which set the fill's level; \"auto\": the input's "
                   "file names in calibration/ beside its frames, where any is there; \"\" "
                   "(off)\n";
      std::cout << "reprojection = " << d["reprojection"].dump()
                << "\n    how the previous frame is found: \"auto\", \"scatter\" or "
                   "\"vector\"\n";
      std::cout << "emission = " << d["emission"].dump()
                << "\n    emitting surfaces: \"auto\", \"direct\" or \"gathered\"\n";
      std::cout << "view_layer = " << d["view_layer"].dump()
                << "\n    view layer of the channels; \"\" detects it\n";
      std::cout << "input_space = " << d["input_space"].dump()
                << "\n    OpenColorIO colour space of the colour passes; \"\" = the config's "
                   "scene_linear role (--input-space overrides)\n";
      std::cout << "passes = " << d["passes"].dump()
                << "\n    G-buffer field -> pass name, or an array of channel names\n";
      std::cout << "outputs = " << d["outputs"].dump()
                << "\n    layers to compute and write (known: ";
      for (size_t k = 0; k < known_outputs().size(); ++k)
        std::cout << (k ? ", " : "") << known_outputs()[k];
      std::cout << ")\n";
      std::cout << "compression = " << d["compression"].dump()
                << "\n    EXR compression of the outputs\n";
    }
  });
}

}  // namespace hbil::cli
