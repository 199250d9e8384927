// display.cpp: see display.h.
#include "io/display.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <functional>

#include "hbil/error.h"
#include "io/exr_output.h"

namespace OCIO = OCIO_NAMESPACE;

namespace hbil::io {

namespace fs = std::filesystem;

namespace {

bool iequals(const std::string& a, const std::string& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// "a", "b", "c" -- for the lists of valid names in error messages.
std::string quoted_list(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "\"" : ", \"") + n + "\"";
  return s.empty() ? "(none)" : s;
}

// The name in `valid` equal to `wanted`, else the one equal ignoring case, else "".
std::string match_name(const std::string& wanted, const std::vector<std::string>& valid) {
  for (const auto& v : valid)
    if (v == wanted) return v;
  for (const auto& v : valid)
    if (iequals(v, wanted)) return v;
  return {};
}

std::string source_words(const std::string& source) {
  if (source == "shipped") return "shipped with hbil";
  return "from " + source;
}

}  // namespace

ConfigChoice choose_config(const std::string& explicit_path, const std::string& shipped_config) {
  if (!explicit_path.empty()) return {explicit_path, "--ocio-config"};
  if (const char* env = std::getenv("OCIO"); env && *env) return {env, "$OCIO"};
  return {shipped_config, "shipped"};
}

struct DisplayTransform::Impl {
  std::string config_path, config_source, input_space, display, view, display_space;
  OCIO::ConstCPUProcessorRcPtr cpu;
};

DisplayTransform::DisplayTransform(const DisplaySettings& s, const std::string& shipped_config) {
  auto impl = std::make_shared<Impl>();
  const ConfigChoice choice = choose_config(s.config_path, shipped_config);
  impl->config_source = choice.source;
  if (choice.path.empty())
    throw Error(Exit::input, "no OCIO config: give one with --ocio-config or $OCIO");
  std::error_code ec;
  impl->config_path = fs::absolute(choice.path, ec).lexically_normal().string();
  if (ec) impl->config_path = choice.path;
  const std::string where =
      "OCIO config " + impl->config_path + " (" + source_words(choice.source) + ")";
  if (!fs::is_regular_file(impl->config_path, ec))
    throw Error(Exit::input, where + ": no such file");

  OCIO::ConstConfigRcPtr config;
  try {
    config = OCIO::Config::CreateFromFile(impl->config_path.c_str());
  } catch (const OCIO::Exception& e) {
    throw Error(Exit::input, where + ": cannot read: " + e.what());
  }

  // Input colour space: names, aliases and roles are all accepted (OCIO resolves them,
  // ignoring case); the canonical name is kept.
  const std::string wanted_space = s.input_space.empty() ? OCIO::ROLE_SCENE_LINEAR : s.input_space;
  OCIO::ConstColorSpaceRcPtr cs = config->getColorSpace(wanted_space.c_str());
  if (!cs) {
    std::vector<std::string> spaces;
    for (int i = 0;
         i < config->getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ACTIVE);
         ++i)
      spaces.emplace_back(config->getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL,
                                                           OCIO::COLORSPACE_ACTIVE, i));
    throw Error(Exit::usage,
                where +
                    (s.input_space.empty()
                         ? std::string(": has no scene_linear role; name the input colour space")
                         : ": no colour space \"" + s.input_space + "\"") +
                    "; its colour spaces are " + quoted_list(spaces) +
                    " (their aliases and the config's roles are accepted too)");
  }
  impl->input_space = cs->getName();

  std::vector<std::string> displays;
  for (int i = 0; i < config->getNumDisplays(); ++i) displays.emplace_back(config->getDisplay(i));
  impl->display = s.display.empty() ? std::string(config->getDefaultDisplay())
                                    : match_name(s.display, displays);
  if (impl->display.empty())
    throw Error(Exit::usage, where +
                                 (s.display.empty() ? std::string(": has no display")
                                                    : ": no display \"" + s.display + "\"") +
                                 "; its displays are " + quoted_list(displays));

  std::vector<std::string> views;
  for (int i = 0; i < config->getNumViews(impl->display.c_str()); ++i)
    views.emplace_back(config->getView(impl->display.c_str(), i));
  impl->view = s.view.empty() ? std::string(config->getDefaultView(impl->display.c_str()))
                              : match_name(s.view, views);
  if (impl->view.empty())
    throw Error(Exit::usage,
                where + ": display \"" + impl->display + "\" has " +
                    (s.view.empty() ? std::string("no view") : "no view \"" + s.view + "\"") +
                    "; its views are " + quoted_list(views));
  impl->display_space =
      config->getDisplayViewColorSpaceName(impl->display.c_str(), impl->view.c_str());

  try {
    OCIO::ConstProcessorRcPtr p =
        config->getProcessor(impl->input_space.c_str(), impl->display.c_str(), impl->view.c_str(),
                             OCIO::TRANSFORM_DIR_FORWARD);
    // The exact log/exp/pow rather than OCIO's SSE approximations: the same numbers on
    // every CPU, and 0.18 -> 0.4614 to 4 digits. Display images are small; speed is moot.
    const auto flags = static_cast<OCIO::OptimizationFlags>(OCIO::OPTIMIZATION_DEFAULT &
                                                            ~OCIO::OPTIMIZATION_FAST_LOG_EXP_POW);
    impl->cpu = p->getOptimizedCPUProcessor(OCIO::BIT_DEPTH_F32, OCIO::BIT_DEPTH_F32, flags);
  } catch (const OCIO::Exception& e) {
    throw Error(Exit::input, where + ": cannot build the transform " + impl->input_space +
                                 " -> display " + impl->display + ", view " + impl->view + ": " +
                                 e.what());
  }
  impl_ = std::move(impl);
}

std::string DisplayTransform::describe() const {
  return std::string("OCIO ") + OCIO::GetVersion() + " config " + impl_->config_path + " (" +
         source_words(impl_->config_source) + "); " + impl_->input_space + " -> display " +
         impl_->display + ", view " + impl_->view + " (" + impl_->display_space + ")";
}

const std::string& DisplayTransform::config_path() const {
  return impl_->config_path;
}
const std::string& DisplayTransform::config_source() const {
  return impl_->config_source;
}
const std::string& DisplayTransform::input_space() const {
  return impl_->input_space;
}
const std::string& DisplayTransform::display() const {
  return impl_->display;
}
const std::string& DisplayTransform::view() const {
  return impl_->view;
}
const std::string& DisplayTransform::display_space() const {
  return impl_->display_space;
}

void DisplayTransform::apply(std::vector<float>& pixels, int width, int height,
                             int channels) const {
  if ((channels != 3 && channels != 4) || width < 0 || height < 0 ||
      pixels.size() != size_t(width) * size_t(height) * size_t(channels))
    throw Error(Exit::failure, "DisplayTransform::apply: " + std::to_string(pixels.size()) +
                                   " floats for " + std::to_string(width) + "x" +
                                   std::to_string(height) + " pixels of " +
                                   std::to_string(channels) + " channels");
  if (width == 0 || height == 0) return;
  const ptrdiff_t px_bytes = ptrdiff_t(channels) * ptrdiff_t(sizeof(float));
  // One row per call: OCIO processes pixels in SIMD groups, so a row's results must not
  // depend on where a thread's share of the image begins.
  tbb::parallel_for(0, height, [&](int y) {
    // RGB ordering with the pixel stride: the 4th float (alpha) is never read or written.
    OCIO::PackedImageDesc row(pixels.data() + size_t(y) * size_t(width) * size_t(channels), width,
                              1, OCIO::CHANNEL_ORDERING_RGB, OCIO::BIT_DEPTH_F32,
                              ptrdiff_t(sizeof(float)), px_bytes, px_bytes * width);
    impl_->cpu->apply(row);
  });
}

bool is_display_image_path(const std::string& path) {
  const std::string ext = lower(fs::path(path).extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".exr";
}

std::string write_display_temporary(const std::string& final_path, const std::vector<float>& pixels,
                                    int channels, int width, int height, const DisplayTransform& t,
                                    const std::string& extra_description) {
  const fs::path final_p(final_path);
  const std::string ext = lower(final_p.extension().string());
  if (!is_display_image_path(final_path))
    throw Error(Exit::output, final_path + ": unsupported display image type \"" +
                                  final_p.extension().string() +
                                  "\"; use .png, .jpg, .jpeg or .exr");
  if ((channels != 1 && channels != 3 && channels != 4) || width <= 0 || height <= 0 ||
      pixels.size() != size_t(width) * size_t(height) * size_t(channels))
    throw Error(Exit::failure, final_path + ": " + std::to_string(pixels.size()) + " floats for " +
                                   std::to_string(width) + "x" + std::to_string(height) +
                                   " pixels of " + std::to_string(channels) + " channels");

  // Grey is replicated to RGB: the view may tint neutrals slightly (ACES), and the file
  // should show what the transform produced.
  const int tc = channels == 4 ? 4 : 3;
  const bool exr = ext == ".exr", jpeg = ext == ".jpg" || ext == ".jpeg";
  const int fc = jpeg ? 3 : tc;  // JPEG has no alpha
  OIIO::ImageSpec spec(width, height, fc, exr ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
  spec.channelnames = {"R", "G", "B"};
  if (fc == 4) spec.channelnames.push_back("A");
  spec.alpha_channel = fc == 4 ? 3 : -1;
  spec.z_channel = -1;
  if (exr) spec.attribute("compression", "zip");
  if (jpeg) spec.attribute("compression", "jpeg:95");
  // PNG: zlib level 1 and no row filter. On the 1920x1080 composites of the samples that
  // writes in 0.17 s a file smaller than level 1 with libpng's adaptive filters (3.9 against
  // 4.8 MB, 0.24 s) or the default level 6 (4.6 MB, 0.62 s).
  if (!exr && !jpeg) {
    spec.attribute("png:compressionLevel", 1);
    spec.attribute("png:filter", 8);  // PNG_FILTER_NONE
  }
  // PNG gets straight colour (see above): OpenImageIO must not divide it by alpha again.
  if (fc == 4 && !exr) spec.attribute("oiio:UnassociatedAlpha", 1);
  spec.attribute("Software", "hbil " HBIL_VERSION);
  spec.attribute("hbil:version", HBIL_VERSION);
  spec.attribute("hbil:ocio", t.describe());
  if (!extra_description.empty()) spec.attribute("ImageDescription", extra_description);

  Temporary tmp(final_path, "display");
  auto out = OIIO::ImageOutput::create(tmp.path());
  if (!out)
    throw Error(Exit::output, final_path + ": cannot create an image writer: " + OIIO::geterror());
  // Transformed and written in strips of rows (each row is transformed on its own, so the
  // strips do not change the result), so that no copy of the whole image is made.
  constexpr int kStrip = 64;
  std::vector<float> buf;
  std::vector<uint8_t> bytes;
  bool ok = out->open(tmp.path(), spec);
  for (int y0 = 0; ok && y0 < height; y0 += kStrip) {
    const int rows = std::min(kStrip, height - y0);
    const size_t first = size_t(y0) * size_t(width), n = size_t(rows) * size_t(width);
    buf.resize(n * tc);
    if (channels == 1) {
      for (size_t i = 0; i < n; ++i)
        buf[3 * i] = buf[3 * i + 1] = buf[3 * i + 2] = pixels[first + i];
    } else {
      std::copy_n(pixels.begin() + std::ptrdiff_t(first * tc), n * tc, buf.begin());
    }
    if (tc == 4)  // premultiplied -> straight, for the transform
      for (size_t i = 0; i < n; ++i) {
        float* px = &buf[4 * i];
        const float k = px[3] > 0 ? 1.0f / px[3] : 0.0f;
        px[0] *= k, px[1] *= k, px[2] *= k;
      }
    t.apply(buf, width, rows, tc);
    if (tc == 4 && (exr || jpeg))  // EXR premultiplied again, JPEG over black; PNG straight
      for (size_t i = 0; i < n; ++i) {
        float* px = &buf[4 * i];
        px[0] *= px[3], px[1] *= px[3], px[2] *= px[3];
      }
    if (exr) {
      ok = out->write_scanlines(y0, y0 + rows, 0, OIIO::TypeDesc::FLOAT, buf.data());
      continue;
    }
    // 8 bits: round(255 * clamp(v, 0, 1)); NaN -> 0.
    bytes.resize(n * fc);
    tbb::parallel_for(0, rows, [&](int r) {
      for (size_t i = size_t(r) * width; i < size_t(r + 1) * width; ++i)
        for (int c = 0; c < fc; ++c) {
          const float v = buf[i * tc + c];
          // v + 0.5 truncated is lround for the non-negative values left after the clamp.
          bytes[i * fc + c] =
              std::isnan(v) ? 0 : uint8_t(255.0f * std::clamp(v, 0.0f, 1.0f) + 0.5f);
        }
    });
    ok = out->write_scanlines(y0, y0 + rows, 0, OIIO::TypeDesc::UINT8, bytes.data());
  }
  ok = ok && out->close();
  if (!ok) {
    const std::string why = out->geterror();
    out.reset();
    throw Error(Exit::output, final_path + ": cannot write: " + why);
  }
  out.reset();
  return tmp.keep();
}

void write_display_image(const std::string& path, const std::vector<float>& pixels, int channels,
                         int width, int height, const DisplayTransform& t,
                         const std::string& extra_description) {
  commit(write_display_temporary(path, pixels, channels, width, height, t, extra_description),
         path);
}

}  // namespace hbil::io
