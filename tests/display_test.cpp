// display_test.cpp: OCIO display transforms and display images (io/display.h), and the
// shipped config presets/ocio/hbil.ocio.
//
// Analytic values: the Standard views are the displays' inverse EOTFs with no tone
// mapping, so 0.18 scene linear must give the closed forms below. The ACES view has no
// short closed form (RRT + ODT splines); its values are regression numbers from OCIO
// 2.1.2's builtin transforms. Tolerances are set once, here.

#include "io/display.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hbil/error.h"
#include "test_util.h"

namespace OCIO = OCIO_NAMESPACE;

namespace hbil::io {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::expect_error;
using test::TempDir;

const std::string kShipped = std::string(HBIL_SOURCE_DIR) + "/presets/ocio/hbil.ocio";
const std::string kBlenderConfig = "/usr/share/blender/datafiles/colormanagement/config.ocio";

// IEC 61966-2-1 sRGB encoding (the inverse of the piecewise EOTF).
double srgb_encode(double l) {
  return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

// sRGB / Standard, 0.18: 1.055 * 0.18^(1/2.4) - 0.055 = 0.461356.
const double kSrgb018 = srgb_encode(0.18);
// Rec.1886 / Standard, 0.18: BT.1886's EOTF L = a * max(V + b, 0)^2.4 with black Lb = 0
// (what OCIO's "DISPLAY - CIE-XYZ-D65_to_REC.1886-REC.709" assumes) gives b = 0, a = Lw = 1,
// so V = L^(1/2.4) = 0.18^(1/2.4) = 0.489437. (The brief's 0.4899 is a rounding slip:
// 0.4899 would need gamma 2.402.)
const double kRec1886018 = std::pow(0.18, 1.0 / 2.4);
constexpr double kCurveTol = 0.0005;  // brief: 0.4614 +- 0.0005; measured error < 1e-6
// Standard on colours: Rec.709 -> AP1 -> AP0 -> XYZ D65 -> Rec.709 is the identity up to
// the rounding of OCIO's builtin matrices (measured < 1e-5 after encoding).
constexpr double kMatrixChainTol = 2e-4;
// ACES 1.0 SDR-video, 0.18 scene linear grey (Linear Rec.709): regression values from
// OCIO 2.1.2's builtin "ACES-OUTPUT - ACES2065-1_to_CIE-XYZ-D65 - SDR-VIDEO_1.0" followed by
// the display's encoding (measured 0.355954 sRGB, 0.389530 Rec.1886: 18 % grey lands near
// 10 nits of 100, as the ACES RRT intends).
constexpr double kAcesSrgb018 = 0.35595;
constexpr double kAcesRec1886018 = 0.38953;
constexpr double kAcesTol = 0.002;

// Environment variable set for one scope, restored afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::optional<std::string>& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      setenv(name, value->c_str(), 1);
    else
      unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// 0.18 grey (or any grey) through a transform: the first channel of the result.
float grey(const DisplayTransform& t, float v) {
  std::vector<float> px{v, v, v};
  t.apply(px, 1, 1);
  EXPECT_FLOAT_EQ(px[0], px[1]);
  EXPECT_FLOAT_EQ(px[0], px[2]);
  return px[0];
}

DisplayTransform shipped(const std::string& display, const std::string& view,
                         const std::string& space = "") {
  return DisplayTransform(DisplaySettings{kShipped, space, display, view}, kShipped);
}

// ---------------------------------------------------------------------------------------
// The shipped config

TEST(ShippedConfig, LoadsAndValidates) {
  OCIO::ConstConfigRcPtr c = OCIO::Config::CreateFromFile(kShipped.c_str());
  ASSERT_TRUE(c);
  EXPECT_NO_THROW(c->validate());
  EXPECT_STREQ(c->getColorSpace("scene_linear")->getName(), "Linear Rec.709 (sRGB)");
  EXPECT_STREQ(c->getColorSpace("Linear")->getName(), "Linear Rec.709 (sRGB)");  // Blender's
  EXPECT_STREQ(c->getDefaultDisplay(), "sRGB");
  ASSERT_EQ(c->getNumDisplays(), 2);
  EXPECT_STREQ(c->getDisplay(0), "sRGB");
  EXPECT_STREQ(c->getDisplay(1), "Rec.1886");
  for (const char* d : {"sRGB", "Rec.1886"}) {
    ASSERT_EQ(c->getNumViews(d), 3) << d;
    EXPECT_STREQ(c->getView(d, 0), "Standard");
    EXPECT_STREQ(c->getView(d, 1), "ACES 1.0 SDR-video");
    EXPECT_STREQ(c->getView(d, 2), "Raw");
    EXPECT_STREQ(c->getDefaultView(d), "Standard");
  }
  for (const char* s : {"Linear Rec.709 (sRGB)", "ACEScg", "ACES2065-1", "sRGB - Display",
                        "Rec.1886 Rec.709 - Display", "Raw"})
    EXPECT_TRUE(c->getColorSpace(s)) << s;
  EXPECT_TRUE(c->getColorSpace("Raw")->isData());
}

// No LUT files: a copy of the config alone in an empty folder gives every display/view.
TEST(ShippedConfig, NeedsNoOtherFiles) {
  TempDir dir(test::test_name());
  const std::string copy = dir / "hbil.ocio";
  fs::copy_file(kShipped, copy);
  for (const char* d : {"sRGB", "Rec.1886"})
    for (const char* v : {"Standard", "ACES 1.0 SDR-video", "Raw"}) {
      DisplayTransform t(DisplaySettings{copy, "", d, v}, kShipped);
      EXPECT_EQ(t.config_path(), copy);
      EXPECT_GT(grey(t, 0.18f), 0.0f) << d << " / " << v;
    }
}

// ACEScg <-> Linear Rec.709 is a change of primaries only: a grey stays the same grey, and
// ACEScg 0.18 shows as 0.4614 in sRGB / Standard.
TEST(ShippedConfig, ScenesSpacesAgreeOnGrey) {
  for (const char* space : {"ACEScg", "ACES2065-1", "lin_ap1"})
    EXPECT_NEAR(grey(shipped("sRGB", "Standard", space), 0.18f), kSrgb018, kCurveTol) << space;
}

// ---------------------------------------------------------------------------------------
// Settings: defaults, names, config precedence

TEST(DisplayTransform, DefaultsComeFromTheConfig) {
  ScopedEnv env("OCIO", std::nullopt);
  DisplayTransform t(DisplaySettings{}, kShipped);
  EXPECT_EQ(t.config_source(), "shipped");
  EXPECT_EQ(t.config_path(), fs::path(kShipped).lexically_normal().string());
  EXPECT_EQ(t.input_space(), "Linear Rec.709 (sRGB)");
  EXPECT_EQ(t.display(), "sRGB");
  EXPECT_EQ(t.view(), "Standard");
  EXPECT_EQ(t.display_space(), "sRGB - Display");
  const std::string d = t.describe();
  EXPECT_TRUE(contains(d, "config " + t.config_path() + " (shipped with hbil)")) << d;
  EXPECT_TRUE(contains(d, "Linear Rec.709 (sRGB) -> display sRGB, view Standard")) << d;
  EXPECT_TRUE(contains(d, std::string("OCIO ") + OCIO::GetVersion())) << d;
}

TEST(DisplayTransform, AliasesRolesAndCaseResolveToCanonicalNames) {
  const DisplayTransform t = shipped("srgb", "aces 1.0 sdr-VIDEO", "Linear");
  EXPECT_EQ(t.input_space(), "Linear Rec.709 (sRGB)");
  EXPECT_EQ(t.display(), "sRGB");
  EXPECT_EQ(t.view(), "ACES 1.0 SDR-video");
  EXPECT_EQ(shipped("", "", "scene_linear").input_space(), "Linear Rec.709 (sRGB)");
  EXPECT_EQ(shipped("", "", "compositing_log").input_space(), "ACEScct");
  EXPECT_EQ(shipped("Rec.1886", "").view(), "Standard");
}

TEST(DisplayTransform, ConfigPrecedence) {
  {
    ScopedEnv env("OCIO", std::nullopt);
    const ConfigChoice c = choose_config("", "/ship.ocio");
    EXPECT_EQ(c.path, "/ship.ocio");
    EXPECT_EQ(c.source, "shipped");
  }
  {
    ScopedEnv env("OCIO", "");  // set but empty counts as unset
    EXPECT_EQ(choose_config("", "/ship.ocio").source, "shipped");
  }
  {
    ScopedEnv env("OCIO", "/env.ocio");
    const ConfigChoice from_env = choose_config("", "/ship.ocio");
    EXPECT_EQ(from_env.path, "/env.ocio");
    EXPECT_EQ(from_env.source, "$OCIO");
    const ConfigChoice explicit_wins = choose_config("/cli.ocio", "/ship.ocio");
    EXPECT_EQ(explicit_wins.path, "/cli.ocio");
    EXPECT_EQ(explicit_wins.source, "--ocio-config");
  }
}

// Blender's own config as "another config": through $OCIO, and overridden by an explicit path.
TEST(DisplayTransform, OcioVariableAndExplicitPathWithBlendersConfig) {
  if (!fs::exists(kBlenderConfig)) GTEST_SKIP() << kBlenderConfig << " absent";
  ScopedEnv env("OCIO", kBlenderConfig);
  {
    const DisplayTransform t(DisplaySettings{"", "", "sRGB", "Standard"}, kShipped);
    EXPECT_EQ(t.config_source(), "$OCIO");
    EXPECT_EQ(t.config_path(), kBlenderConfig);
    EXPECT_EQ(t.input_space(), "Linear");  // Blender's scene_linear role
    EXPECT_TRUE(contains(t.describe(), "(from $OCIO)")) << t.describe();
    // Blender's Standard is a 1D LUT of the same sRGB curve (FACTS.md: 0.18 -> 0.4614).
    EXPECT_NEAR(grey(t, 0.18f), kSrgb018, kCurveTol);
  }
  {
    // Blender's config has no "Rec.1886" display: that it is accepted proves the explicit
    // (shipped) path won over $OCIO.
    const DisplayTransform t(DisplaySettings{kShipped, "", "Rec.1886", "Standard"}, kShipped);
    EXPECT_EQ(t.config_source(), "--ocio-config");
    EXPECT_EQ(t.config_path(), fs::path(kShipped).lexically_normal().string());
    EXPECT_NEAR(grey(t, 0.18f), kRec1886018, kCurveTol);
  }
}

TEST(DisplayTransform, UnknownNamesListTheValidOnes) {
  expect_error([] { shipped("sRGB", "Standard", "Filmic Log"); }, Exit::usage,
               {"\"Filmic Log\"", kShipped, "\"Linear Rec.709 (sRGB)\"", "\"ACEScg\"",
                "\"ACES2065-1\"", "\"Raw\""});
  expect_error([] { shipped("P3", "Standard"); }, Exit::usage,
               {"no display \"P3\"", "\"sRGB\"", "\"Rec.1886\""});
  expect_error([] { shipped("Rec.1886", "Filmic"); }, Exit::usage,
               {"display \"Rec.1886\" has no view \"Filmic\"", "\"Standard\"",
                "\"ACES 1.0 SDR-video\"", "\"Raw\""});
}

TEST(DisplayTransform, UnreadableConfigsAreInputErrors) {
  TempDir dir(test::test_name());
  expect_error(
      [&] {
        DisplayTransform(DisplaySettings{dir / "none.ocio", "", "", ""}, kShipped);
      },
      Exit::input, {dir / "none.ocio", "no such file"});
  test::write_text(dir / "garbage.ocio", "this: [is not, an OCIO config\n");
  expect_error(
      [&] {
        DisplayTransform(DisplaySettings{dir / "garbage.ocio", "", "", ""}, kShipped);
      },
      Exit::input, {dir / "garbage.ocio", "cannot read"});
  // A config that parses but whose view needs a LUT file that is not there.
  std::string text = test::read_text(kShipped);
  const std::string builtin = "!<BuiltinTransform> {style: DISPLAY - CIE-XYZ-D65_to_sRGB}";
  ASSERT_TRUE(contains(text, builtin));
  text.replace(text.find(builtin), builtin.size(), "!<FileTransform> {src: missing.spi1d}");
  test::write_text(dir / "lut.ocio", text);
  expect_error(
      [&] {
        DisplayTransform(DisplaySettings{dir / "lut.ocio", "", "", ""}, kShipped);
      },
      Exit::input, {dir / "lut.ocio", "missing.spi1d"});
  // No config at all: no path, no $OCIO, no shipped file.
  ScopedEnv env("OCIO", std::nullopt);
  expect_error([] { DisplayTransform(DisplaySettings{}, ""); }, Exit::input,
               {"--ocio-config", "$OCIO"});
}

// ---------------------------------------------------------------------------------------
// Values

TEST(DisplayTransform, SrgbStandardIsThePiecewiseCurve) {
  const DisplayTransform t = shipped("sRGB", "Standard");
  EXPECT_NEAR(grey(t, 0.18f), kSrgb018, kCurveTol);  // 0.4614
  EXPECT_NEAR(grey(t, 0.0f), 0.0, 1e-6);
  EXPECT_NEAR(grey(t, 1.0f), 1.0, 1e-5);
  EXPECT_NEAR(grey(t, 0.002f), 12.92 * 0.002, 1e-5);  // the linear toe
  // Per channel on colours: no gamut mapping, no tone mapping.
  std::vector<float> px;
  for (int i = 0; i < 64; ++i) px.push_back(float((i * 37) % 101) / 100.0f);
  std::vector<float> out = px;
  t.apply(out, int(px.size() / 4), 1, 3 + 1);  // RGBA: the 4th value must stay as it was
  for (size_t i = 0; i < px.size(); ++i) {
    if (i % 4 == 3)
      EXPECT_EQ(out[i], px[i]) << "alpha " << i;
    else
      EXPECT_NEAR(out[i], srgb_encode(px[i]), kMatrixChainTol) << i << ": " << px[i];
  }
}

TEST(DisplayTransform, Rec1886StandardIsTheInverse24Power) {
  const DisplayTransform t = shipped("Rec.1886", "Standard");
  const float v = grey(t, 0.18f);
  EXPECT_NEAR(v, kRec1886018, kCurveTol) << "0.18^(1/2.4) = " << kRec1886018;
  EXPECT_NEAR(grey(t, 0.0f), 0.0, 1e-6);
  EXPECT_NEAR(grey(t, 1.0f), 1.0, 1e-5);
  EXPECT_NEAR(grey(t, 0.5f), std::pow(0.5, 1 / 2.4), kCurveTol);
}

TEST(DisplayTransform, AcesViewRegressionAndMonotonic) {
  for (const auto& [display, expected] :
       {std::pair{"sRGB", kAcesSrgb018}, std::pair{"Rec.1886", kAcesRec1886018}}) {
    const DisplayTransform t = shipped(display, "ACES 1.0 SDR-video");
    const float v = grey(t, 0.18f);
    std::printf("[ measured ] ACES 1.0 SDR-video, display %s: 0.18 -> %.6f\n", display, v);
    EXPECT_NEAR(v, expected, kAcesTol) << display;
    // A ramp from 0 to 64 (log-spaced above 2^-12): non-decreasing and rising to about 1.
    // Not clipped at 1: OCIO's builtin omits the ACES CTL ODT's final clamp to [0, 1], so
    // scene values over about 16 come out slightly above 1 (64 -> 1.017, 2^16 -> 1.040
    // with OCIO 2.1.2); 8-bit display images clamp them.
    std::vector<float> ramp{0, 0, 0};
    for (double e = -12; e <= 6.0001; e += 0.125) ramp.insert(ramp.end(), 3, float(std::exp2(e)));
    const int n = int(ramp.size() / 3);
    t.apply(ramp, n, 1);
    for (int i = 1; i < n; ++i) EXPECT_GE(ramp[3 * i], ramp[3 * (i - 1)]) << display << " " << i;
    EXPECT_GE(ramp[0], 0.0f);
    EXPECT_GT(ramp[3 * (n - 1)], 0.99f) << display;
    EXPECT_LT(ramp[3 * (n - 1)], 1.05f) << display;
  }
}

TEST(DisplayTransform, RawViewChangesNothing) {
  const DisplayTransform t = shipped("sRGB", "Raw");
  std::vector<float> px{0.18f, -1.0f, 16.0f}, before = px;
  t.apply(px, 1, 1);
  EXPECT_EQ(px, before);
}

// Rows are processed one per task: any thread count gives the same bytes.
TEST(DisplayTransform, ThreadCountDoesNotChangeResults) {
  const DisplayTransform t = shipped("sRGB", "ACES 1.0 SDR-video");
  const int w = 37, h = 23;  // widths that are not multiples of the SIMD width
  std::vector<float> a(size_t(w) * h * 3);
  for (size_t i = 0; i < a.size(); ++i) a[i] = float(std::exp2(double(i % 97) / 8.0 - 8.0));
  std::vector<float> b = a;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    t.apply(a, w, h);
  }
  t.apply(b, w, h);
  EXPECT_EQ(a, b);
}

TEST(DisplayTransform, WrongBufferSizeIsAnInternalError) {
  const DisplayTransform t = shipped("", "");
  std::vector<float> px(10);
  expect_error([&] { t.apply(px, 2, 2); }, Exit::failure, {"10 floats", "2x2"});
  expect_error([&] { t.apply(px, 1, 1, 2); }, Exit::failure, {"2 channels"});
}

// ---------------------------------------------------------------------------------------
// Display images

test::Pixels read_back(const std::string& path) {
  return test::read_pixels(path);
}

TEST(DisplayImage, PngHoldsRoundedEightBitValues) {
  TempDir dir(test::test_name());
  const DisplayTransform t = shipped("sRGB", "Standard");
  const std::string path = dir / "new/folder/grey.png";  // folders are created
  // Grey in 1 channel: 0.18, 0, 1, 4 (clamped), -1 (clamped).
  const std::vector<float> px{0.18f, 0.0f, 1.0f, 4.0f, -1.0f, 0.18f};
  write_display_image(path, px, 1, 3, 2, t, "ao of frame 1");
  ASSERT_TRUE(fs::exists(path));
  EXPECT_TRUE(test::files_containing(dir.path(), "hbil-tmp").empty());

  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in) << OIIO::geterror();
  const OIIO::ImageSpec spec = in->spec();
  EXPECT_EQ(spec.nchannels, 3);
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT8);
  std::vector<uint8_t> bytes(size_t(3 * 2 * 3));
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, bytes.data()));
  const int expected = int(std::lround(255 * kSrgb018));  // round(117.65) = 118
  EXPECT_EQ(expected, 118);
  const int want[6] = {expected, 0, 255, 255, 0, expected};
  for (int i = 0; i < 6; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(int(bytes[3 * i + c]), want[i]) << i << "," << c;
  EXPECT_EQ(spec.get_string_attribute("hbil:ocio"), t.describe());
  EXPECT_EQ(spec.get_string_attribute("ImageDescription"), "ao of frame 1");
}

TEST(DisplayImage, PngKeepsStraightAlpha) {
  TempDir dir(test::test_name());
  const DisplayTransform t = shipped("sRGB", "Standard");
  // Premultiplied 0.09 at alpha 0.5: straight 0.18 goes through the view.
  write_display_image(dir / "a.png", {0.09f, 0.09f, 0.09f, 0.5f}, 4, 1, 1, t, "");
  // Read as stored: OIIO would otherwise premultiply on reading.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(dir / "a.png", &config);
  ASSERT_TRUE(in) << OIIO::geterror();
  ASSERT_EQ(in->spec().nchannels, 4);
  uint8_t px[4];
  ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, px));
  EXPECT_EQ(int(px[0]), 118);
  EXPECT_EQ(int(px[3]), 128);  // round(127.5)
}

TEST(DisplayImage, ExrIsHalfAndDisplayReferred) {
  TempDir dir(test::test_name());
  const DisplayTransform t = shipped("Rec.1886", "Standard");
  write_display_image(dir / "d.exr", {0.18f, 0.18f, 0.18f, 0.25f, 4.0f, 4.0f, 4.0f, 1.0f}, 4, 2, 1,
                      t, "");
  const test::Pixels p = read_back(dir / "d.exr");
  EXPECT_EQ(p.spec.format, OIIO::TypeDesc::HALF);
  ASSERT_EQ(p.spec.nchannels, 4);
  // Premultiplied 0.18 at alpha 0.25: straight 0.72 through the view, premultiplied again.
  EXPECT_NEAR(p.at(0, 0, 0), 0.25 * std::pow(0.72, 1 / 2.4), 5e-4);  // half: 11-bit mantissa
  EXPECT_EQ(p.at(0, 0, 3), 0.25f);
  EXPECT_NEAR(p.at(1, 0, 0), std::pow(4.0, 1 / 2.4), 2e-3);  // not clamped
  EXPECT_EQ(p.spec.get_string_attribute("hbil:ocio"), t.describe());
  EXPECT_TRUE(test::files_containing(dir.path(), "hbil-tmp").empty());
}

// A film-transparent Cycles render (samples/blender/transparent.py): Combined is
// premultiplied, with fractional alpha along every silhouette. The PNG holds straight
// colour: each pixel's 8-bit value is the view of Combined / alpha, and its alpha is
// Combined's. Writing the premultiplied values as straight (what the PNG held before)
// darkens every edge pixel; the test counts how many pixels tell the two apart.
TEST(DisplayImage, FilmTransparentRenderGivesAStraightAlphaPng) {
  TempDir dir(test::test_name());
  const test::Pixels src =
      test::read_pixels(test::kSourceDir + "/tests/data/transparent/frame_0001.exr");
  const int w = src.spec.width, h = src.spec.height;
  int ch[4];
  const char* names[4] = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                          "ViewLayer.Combined.A"};
  for (int c = 0; c < 4; ++c) ASSERT_GE(ch[c] = src.spec.channelindex(names[c]), 0) << names[c];
  std::vector<float> rgba(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) rgba[(size_t(y) * w + x) * 4 + c] = src.at(x, y, ch[c]);
  const DisplayTransform t = shipped("sRGB", "Standard");
  write_display_image(dir / "c.png", rgba, 4, w, h, t, "");
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // read as stored
  auto in = OIIO::ImageInput::open(dir / "c.png", &config);
  ASSERT_TRUE(in) << OIIO::geterror();
  std::vector<uint8_t> png(size_t(w) * h * 4);
  ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, png.data()));
  int partial = 0, distinguished = 0, transparent = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    const float a = rgba[4 * i + 3];
    EXPECT_EQ(int(png[4 * i + 3]), int(std::lround(255 * std::clamp(a, 0.f, 1.f)))) << i;
    if (a <= 0) {
      ++transparent;
      for (int c = 0; c < 3; ++c) EXPECT_EQ(int(png[4 * i + c]), 0) << i;
      continue;
    }
    const bool edge = a < 0.99f;
    partial += edge;
    bool differs = false;
    for (int c = 0; c < 3; ++c) {
      const double straight = srgb_encode(std::clamp(double(rgba[4 * i + c]) / a, 0.0, 1.0));
      const double premult = srgb_encode(std::clamp(double(rgba[4 * i + c]), 0.0, 1.0));
      EXPECT_NEAR(png[4 * i + c], 255 * straight, 1.0) << "pixel " << i << " channel " << c;
      differs = differs || std::abs(255 * (straight - premult)) > 2;
    }
    distinguished += edge && differs;
  }
  EXPECT_GT(transparent, w * h / 4);
  EXPECT_GT(partial, 50);
  EXPECT_GT(distinguished, partial / 2);
}

TEST(DisplayImage, JpegDropsAlpha) {
  TempDir dir(test::test_name());
  const DisplayTransform t = shipped("sRGB", "Standard");
  std::vector<float> px;
  for (int i = 0; i < 16 * 16; ++i) px.insert(px.end(), {0.18f, 0.18f, 0.18f, 1.0f});
  write_display_image(dir / "g.JPEG", px, 4, 16, 16, t, "");
  const test::Pixels p = read_back(dir / "g.JPEG");
  ASSERT_EQ(p.spec.nchannels, 3);
  EXPECT_NEAR(p.at(5, 5, 1) * 255.0f, 118.0f, 1.01f);  // lossy, but a flat image survives
}

TEST(DisplayImage, FailuresAreOutputErrorsAndLeaveNothing) {
  TempDir dir(test::test_name());
  const DisplayTransform t = shipped("", "");
  EXPECT_FALSE(is_display_image_path("a.tif"));
  EXPECT_TRUE(is_display_image_path("a/b.Jpg"));
  expect_error([&] { write_display_image(dir / "a.tif", {0.5f}, 1, 1, 1, t, ""); }, Exit::output,
               {"a.tif", ".png, .jpg, .jpeg or .exr"});
  test::write_text(dir / "file", "x");
  expect_error([&] { write_display_image(dir / "file/a.png", {0.5f}, 1, 1, 1, t, ""); },
               Exit::output, {"file/a.png", "cannot create folder"});
  // An existing image is replaced only by a complete one.
  write_display_image(dir / "keep.png", {0.5f}, 1, 1, 1, t, "");
  expect_error(
      [&] {
        write_display_image(dir / "keep.png", {0.5f, 0.5f}, 1, 1, 1, t, "");
      },
      Exit::failure, {"keep.png"});
  EXPECT_TRUE(fs::exists(dir / "keep.png"));
  EXPECT_TRUE(test::files_containing(dir.path(), "hbil-tmp").empty());
}

}  // namespace
}  // namespace hbil::io
