// display.h: display images through OpenColorIO (OCIO 2.1).
//
// hbil's layers are scene-linear data; a display image (PNG, JPEG or a display-referred
// EXR) is made by one OCIO display/view transform:
//
//   input colour space --(config's view transform)--> display colour space
//
// Which config: an explicit path (--ocio-config) wins over $OCIO, which wins over the
// config shipped with hbil (presets/ocio/hbil.ocio: LUT-free, OCIO 2.1 builtin transforms;
// displays sRGB and Rec.1886, views Standard, ACES 1.0 SDR-video and Raw). OCIO 2.1 has
// no built-in configs, and with $OCIO unset OCIO itself would silently fall back to a raw
// config, so hbil never asks OCIO for its "current" config: it always loads a file.
//
// Empty settings take the config's own defaults: the scene_linear role as the input
// space, the default display, that display's default view.
//
// Errors: an unreadable or broken config is Error(Exit::input) naming the file; an
// unknown colour space, display or view is Error(Exit::usage) naming the value and
// listing the valid ones; a display image that cannot be written is Error(Exit::output).
//
// The transform runs on OCIO's CPU processor without its fast (approximate) log, exp and
// pow, one row at a time: a pixel's result depends only on its value and the image
// width, never on the thread count.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace hbil::io {

struct DisplaySettings {
  std::string config_path;  // --ocio-config; "" = $OCIO, else the shipped config
  std::string input_space;  // colour space (or alias, or role) of the pixels; "" = scene_linear
  std::string display;      // "" = the config's default display
  std::string view;         // "" = the display's default view
};

// The config file to use and where that choice came from.
struct ConfigChoice {
  std::string path;    // as given (not made absolute)
  std::string source;  // "--ocio-config", "$OCIO" or "shipped"
};

// explicit_path if not empty, else $OCIO if set and not empty, else shipped_config.
ConfigChoice choose_config(const std::string& explicit_path, const std::string& shipped_config);

class DisplayTransform {
 public:
  // Loads the config chosen by choose_config(s.config_path, shipped_config) and builds
  // the processor. Throws Error(Exit::input) for a missing, unreadable or broken config,
  // Error(Exit::usage) for an unknown input space, display or view.
  DisplayTransform(const DisplaySettings& s, const std::string& shipped_config);

  // "OCIO 2.1.2 config /abs/hbil.ocio (shipped); Linear Rec.709 (sRGB) -> display sRGB,
  // view Standard (sRGB - Display)". Stored as hbil:ocio in every display image.
  std::string describe() const;

  // The resolved names (canonical: aliases and roles replaced by the colour space name).
  const std::string& config_path() const;    // absolute
  const std::string& config_source() const;  // "--ocio-config", "$OCIO" or "shipped"
  const std::string& input_space() const;
  const std::string& display() const;
  const std::string& view() const;
  const std::string& display_space() const;  // the view's output colour space

  // Applies the transform in place to interleaved pixels, `channels` floats per pixel:
  // 3 = RGB, 4 = RGBA (alpha is left untouched; RGB is transformed as given, so callers
  // with premultiplied colour should unpremultiply first). Rows top-down, any order.
  // Throws Error(Exit::failure) if pixels.size() != width * height * channels.
  void apply(std::vector<float>& pixels, int width, int height, int channels = 3) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

// The display image formats, chosen by the extension (case-insensitive):
//   .png, .jpg, .jpeg  8 bits per channel: round(255 * clamp(v, 0, 1)), NaN -> 0
//   .exr               half float, display-referred, unclamped, ZIP
// PNG and EXR keep alpha; JPEG drops it. RGBA is transformed as straight colour (divided
// by alpha; 0 where alpha is 0), since a view transform is not linear. PNG stores that
// straight colour, as PNG defines; EXR multiplies it by alpha again (EXR is premultiplied);
// JPEG shows it over black (also multiplied by alpha). Returns true for those extensions.
bool is_display_image_path(const std::string& path);

// Writes a display image of `pixels` (channels 1 = grey, replicated to RGB before the
// transform; 3 = RGB; 4 = RGBA, colour premultiplied by alpha as in Blender's passes) to
// a temporary file beside `final_path` (creating its folder) and returns the temporary's path;
// io::commit() (exr_output.h) renames it into place. Metadata: hbil:ocio = t.describe(),
// hbil:version, Software, and ImageDescription = extra_description when that is not empty. Throws
// Error(Exit::output), also for an unsupported extension (check is_display_image_path() first to
// report that as a usage error).
std::string write_display_temporary(const std::string& final_path, const std::vector<float>& pixels,
                                    int channels, int width, int height, const DisplayTransform& t,
                                    const std::string& extra_description);

// write_display_temporary() followed by commit(): the file appears complete or not at all.
void write_display_image(const std::string& path, const std::vector<float>& pixels, int channels,
                         int width, int height, const DisplayTransform& t,
                         const std::string& extra_description);

}  // namespace hbil::io
