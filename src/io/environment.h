// environment.h: the distant environment for far-field lighting, read once and reduced to
// its order-2 SH projection (hbil/farfield.h).
#pragma once

#include <string>

#include "hbil/farfield.h"

namespace hbil::io {

// `spec` is either
//  - "rgb:R,G,B": a constant radiance, three finite numbers >= 0 ("rgb:0.1,0.2,0.3");
//    anything else after "rgb:" is Error(Exit::usage) quoting the spec; or
//  - the path of an equirectangular image OIIO can read (EXR, HDR, ...), mapped as Blender's
//    Environment Texture maps it (farfield.h), width = 2 x height. Its subimage 0 is read;
//    colour comes from the channels named R, G, B, or else the first three channels, taken
//    as linear radiance (no colour management).
// Errors name the file: missing or unreadable is Error(Exit::input); fewer than 3 channels,
// a width that is not twice the height, or a non-finite pixel is Error(Exit::bad_data).
SH9 load_environment(const std::string& spec);

}  // namespace hbil::io
