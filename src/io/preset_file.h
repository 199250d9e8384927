// preset_file.h: reading a JSON preset file (--preset).
#pragma once

#include <string>

#include "hbil/params.h"

namespace hbil::io {

// The parameters of the preset file at `path`: keys it does not hold keep their defaults.
// A missing, unreadable or malformed file, an unknown key or a value out of range is
// Error(Exit::preset) naming the path.
Params read_preset(const std::string& path);

}  // namespace hbil::io
