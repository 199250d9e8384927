// exr_frame.h: one input frame of a G-buffer sequence: its header, where each G-buffer
// field lives among its channels, reading only the fields asked for, and its camera.
//
// Channel lookup (Blender 3.4 multilayer EXR, see FACTS.md): channels are named
// <ViewLayer>.<Pass>.<chan> and stored alphabetically, so they are always looked up by
// name, once per frame. Params::passes maps each field to a pass name ("Normal" ->
// <layer>.Normal.X/Y/Z), to a name with a dot ("Combined.A", tried with and without the
// layer prefix), or to an explicit list of channel names (other renderers).
#pragma once

#include <OpenImageIO/imageio.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hbil/camera.h"
#include "hbil/gbuffer.h"
#include "hbil/params.h"

namespace hbil::io {

// Channel suffixes of each G-buffer field, in order.
const std::vector<std::string>& field_components(const std::string& field);

struct InputFrame {
  std::string path;
  int frame = 0;
  int part = 0;            // of a multi-part file: the one holding the passes (its subimage index)
  OIIO::ImageSpec spec;    // that part's
  bool openexr = false;    // an OpenEXR file (read through OpenEXR itself)
  std::string view_layer;  // "" when channels have no layer
  std::map<std::string, std::vector<int>>
      channels;  // field -> channel indices (present fields only)
  std::map<std::string, std::vector<std::string>> wanted;  // field -> channel names looked for

  bool has(const std::string& field) const { return channels.count(field) > 0; }
  // "frame 3 (shot/frame_0003.exr)": the context every error message starts with.
  std::string where() const;
};

// Whether an image's data window differs from its display window (a crop, or an overscan's
// guard band).
bool windowed(const OIIO::ImageSpec& spec);

// Whether the frame's Emit pass is light for the gather to add (Params::emission; "auto": for
// frames `hbil import-povray` wrote), that is whether its DiffDir lacks the emitters' light.
bool emission_gathered(const InputFrame& f, const Params& p);

// Opens the header and resolves the channels. Throws Error(Exit::input) when the file is
// missing or not a readable image.
InputFrame open_frame(const std::string& path, int frame, const Params& p);

// The fields the requested outputs need, given what the frame holds: AO and bent cones need
// depth (or, without it, position) and normal; alpha is read when present. Throws
// Error(Exit::missing_pass) naming the channels looked for.
std::vector<std::string> fields_needed(const InputFrame& f, const Params& p);

// Throws Error(Exit::missing_pass) for the first of `fields` the frame lacks, naming the
// channels looked for and `needed_by` ("irradiance, indirect and composite", "panorama").
void require_fields(const InputFrame& f, const std::vector<std::string>& fields,
                    const std::string& needed_by);
// `p` with outputs "auto" resolved against what this frame holds: ao and bentcone, and each
// of irradiance, indirect and composite whose passes are present. `why_dropped` receives
// the missing-pass message of the first auto output left out ("" when none was).
Params resolve_outputs(const InputFrame& f, const Params& p, std::string* why_dropped = nullptr);

// Reads the given fields (all must be present). Checks the data: a value that is not
// finite in any field, a negative depth, a value beyond +-1e9 in a normal, position or
// colour pass (+-1000 in an albedo pass: DiffCol, GlossCol, TransCol) or a motion vector
// beyond +-1e6 pixels is Error(Exit::bad_data) naming the frame, file, channel, pixel and
// value. Background (depth >= background_depth) is allowed.
// `keep_half`: the colour fields an OpenEXR file stores as half are kept as their bits in
// GBuffer::packed (call GBuffer::unpack() before computing with them).
GBuffer read_fields(const InputFrame& f, const std::vector<std::string>& fields, const Params& p,
                    bool keep_half = false);

// Whether find_camera will solve the camera from Position: no sidecar beside the file, no
// camera attributes in its header, and a Position pass (fields_needed then reads it).
bool camera_from_position(const InputFrame& f);

// The camera of a frame, in the order: sidecar next to the file, EXR worldToCamera and
// worldToNDC attributes, solved from the Position pass (read here when `g` lacks it). A
// solved camera whose RMS reprojection error exceeds max_rms_px is Error(Exit::camera);
// with no source at all the error says what to provide.
Camera find_camera(const InputFrame& f, GBuffer& g, const Params& p, double max_rms_px = 0.5);

}  // namespace hbil::io
