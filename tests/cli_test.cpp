// cli_test.cpp: the hbil binary end to end: exit codes, messages, the files it writes and
// the files it must leave alone.
//
// Each test works in its own temporary folder and runs HBIL_BINARY on the room_poles
// sample (256x144, two frames take well under a second) or on copies of it with a pass
// removed or a pixel broken. A failing run keeps the frames it finished before the failure
// and leaves everything else in its output folder exactly as it was: every failure test puts
// sentinels out_0001.exr and out_0002.exr there first and compares the folder byte for byte
// afterwards, less the frames the failure kept.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hbil/error.h"
#include "hbil/params.h"
#include "hbil/scene_scale.h"
#include "io/camera_io.h"
#include "io/exr_frame.h"
#include "test_util.h"

namespace hbil {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::contains;
using test::Pixels;
using test::q;
using test::RunResult;
using test::TempDir;

constexpr int kSampleW = 256, kSampleH = 144;
// AO with the camera solved from Position against AO with the sidecar camera (RMS, AO
// units). The solve reprojects within 0.001 px on this sample; measured RMS 2e-6.
constexpr double kSolvedCameraAoRmse = 1e-3;

// The default outputs ("auto") on a sample that has every pass: EXR channels in the order
// written (alphabetical by layer after ao and bentcone, as OpenEXR sorts them).
const std::vector<std::string> kOutputChannels = {
    "ao.Y",        "bentcone.X",  "bentcone.Y",   "bentcone.Z",   "bentcone.W",
    "composite.R", "composite.G", "composite.B",  "composite.A",  "indirect.R",
    "indirect.G",  "indirect.B",  "irradiance.R", "irradiance.G", "irradiance.B"};
const std::vector<std::string> kAoChannels = {"ao.Y", "bentcone.X", "bentcone.Y", "bentcone.Z",
                                              "bentcone.W"};

std::string sample(int frame, const std::string& ext = ".exr") {
  char name[32];
  std::snprintf(name, sizeof name, "/frame_%04d", frame);
  return test::kRoomPoles + name + ext;
}

// Every file below `dir` with its bytes.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> s;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) s[fs::relative(e.path(), dir).string()] = test::read_text(e.path());
  return s;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    // The samples are part of the repository: without them every test here would pass
    // without checking anything, so their absence is a failure.
    for (int n = 1; n <= 4; ++n)
      ASSERT_TRUE(fs::exists(sample(n)) && fs::exists(sample(n, ".camera.json")))
          << sample(n) << " (or its sidecar) is absent: the command-line tests need it";
    fs::create_directories(dir.path() / "in");
    fs::create_directories(dir.path() / "out");
  }

  RunResult hbil(const std::string& args) { return test::run_hbil(args, dir.path()); }
  std::string path(const std::string& rel) const { return dir / rel; }

  // in/frame_000N.exr (+ sidecar) copied from the sample.
  void copy_frame(int n, bool sidecar = true) {
    const std::string base = path("in") + sample(n, "").substr(test::kRoomPoles.size());
    fs::copy_file(sample(n), base + ".exr");
    if (sidecar) fs::copy_file(sample(n, ".camera.json"), base + ".camera.json");
  }
  // in/frame_000N.exr (+ sidecar) as links to the sample.
  void link_frame(int n) {
    fs::create_symlink(sample(n), in_frame(n));
    fs::create_symlink(sample(n, ".camera.json"), in_frame(n, ".camera.json"));
  }
  std::string in_frame(int n, const std::string& ext = ".exr") const {
    return path("in") + sample(n, ext).substr(test::kRoomPoles.size());
  }

  // Puts sentinels out_0001.exr and out_0002.exr into out/, runs, and checks the exit code,
  // that stderr holds every needle, and that out/ is byte-identical afterwards (no output,
  // no temporaries) but for the frames `kept`: those were finished before the failure, and
  // their EXR and PNG are hbil's (a complete EXR with hbil's layers) in place of the sentinel.
  RunResult expect_failure(const std::string& args, Exit code,
                           std::initializer_list<std::string> needles,
                           std::initializer_list<int> kept = {}) {
    const std::string sentinel = "previous output, must survive a failed run\n";
    test::write_text(path("out/out_0001.exr"), sentinel);
    test::write_text(path("out/out_0002.exr"), sentinel);
    auto before = snapshot(path("out"));
    const RunResult r = hbil(args);
    EXPECT_EQ(r.code, int(code)) << "stderr: " << r.err;
    for (const auto& n : needles)
      EXPECT_TRUE(contains(r.err, n)) << "stderr \"" << r.err << "\" lacks \"" << n << "\"";
    auto after = snapshot(path("out"));
    for (int f : kept) {
      const std::string exr = "out_000" + std::to_string(f) + ".exr";
      const std::string png = "out_000" + std::to_string(f) + ".png";
      EXPECT_TRUE(after.count(exr) && after.count(png)) << "frame " << f << " was finished";
      if (after.count(exr))
        EXPECT_EQ(test::read_pixels(path("out/" + exr)).spec.channelnames, kOutputChannels);
      after.erase(exr);
      after.erase(png);
      before.erase(exr);
    }
    EXPECT_EQ(after, before) << "a failed run changed what it had not finished";
    EXPECT_TRUE(test::files_containing(dir.path(), ".hbil-tmp").empty());
    return r;
  }

  TempDir dir{test::test_name()};
};

std::string run_args(const std::string& in_pattern, const std::string& out_pattern,
                     const std::string& extra = "") {
  return "run " + q(in_pattern) + " -o " + q(out_pattern) + " " + extra;
}

// unseen_radiance "auto" says what it does, where a gathered output uses it, and what it
// takes beyond the frame (the interior preset carries the frame's top and bottom); 0 says
// nothing.
TEST_F(Cli, RunSaysWhatUnseenRadianceAutoDoes) {
  const std::string interior = q(std::string(HBIL_SOURCE_DIR) + "/presets/interior.json");
  const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("a/f_####.exr"),
                                    "--frames 1 --no-display --preset " + interior));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "hbil: unseen_radiance auto: per frame, 0.8 x the mean")) << r.err;
  EXPECT_TRUE(contains(r.err, "the elevations it does not show as open as its top and bottom"))
      << r.err;
  const RunResult off = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("c/f_####.exr"),
                                      "--frames 1 --no-display --set unseen_radiance=0"));
  ASSERT_EQ(off.code, 0) << off.err;
  EXPECT_FALSE(contains(off.err, "unseen_radiance")) << off.err;
  const RunResult ao =
      hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("b/f_####.exr"),
                    "--frames 1 --no-display --preset " + interior + " --set 'outputs=[\"ao\"]'"));
  ASSERT_EQ(ao.code, 0) << ao.err;
  EXPECT_FALSE(contains(ao.err, "unseen_radiance")) << ao.err;
}

TEST_F(Cli, RunWritesLayersAndMetadata) {
  const RunResult r = hbil(
      run_args(test::kRoomPoles + "/frame_####.exr", path("out/out_####.exr"), "--frames 1-2"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "frame 1 (1/2)")) << r.err;
  EXPECT_TRUE(contains(r.err, "camera: sidecar frame_0002.camera.json")) << r.err;
  EXPECT_TRUE(contains(r.err, "hbil: outputs: ao, bentcone, irradiance, indirect, composite"))
      << r.err;
  // unseen_radiance "auto" by default, the elevations the frame does not show escaping.
  EXPECT_TRUE(contains(r.err, "hbil: unseen_radiance auto: per frame")) << r.err;
  EXPECT_TRUE(contains(r.err, "the elevations it does not show escaping")) << r.err;
  EXPECT_TRUE(contains(r.err, "display images " + path("out/out_####.png") + " (composite)"))
      << r.err;
  const auto files = snapshot(path("out"));
  EXPECT_EQ(files.size(), 4u) << "exactly out_000{1,2}.exr and their sRGB PNGs";
  for (const char* png : {"out_0001.png", "out_0002.png"}) {
    ASSERT_TRUE(files.count(png)) << png;
    const Pixels img = test::read_pixels(path(std::string("out/") + png));
    EXPECT_EQ(img.spec.width, kSampleW);
    EXPECT_EQ(img.spec.nchannels, 4) << "RGBA: the composite's alpha";
    EXPECT_TRUE(contains(img.spec.get_string_attribute("ImageDescription"), "composite"));
  }
  EXPECT_TRUE(test::files_containing(dir.path(), ".hbil-tmp").empty());

  for (int frame : {1, 2}) {
    SCOPED_TRACE(frame);
    const std::string out = path("out/out_000" + std::to_string(frame) + ".exr");
    const Pixels px = test::read_pixels(out);
    ASSERT_EQ(px.spec.width, kSampleW);
    ASSERT_EQ(px.spec.height, kSampleH);
    std::vector<std::string> names(px.spec.channelnames.begin(), px.spec.channelnames.end());
    EXPECT_EQ(names, kOutputChannels);

    // Metadata: the effective preset, the version, the camera, the input's stamp.
    // Metadata holds the preset as run, "auto" resolved, so that it reproduces the file.
    const json preset = json::parse(px.spec.get_string_attribute("hbil:preset"));
    // gather_radius and thickness "auto" from the first frame (scene_scale.h).
    Params as_run;
    as_run.outputs = auto_outputs();
    {
      const io::InputFrame f1 = io::open_frame(test::kRoomPoles + "/frame_0001.exr", 1, as_run);
      GBuffer g = io::read_fields(f1, {"depth"}, as_run);
      as_run =
          resolve_scene_params(as_run, measure_scene(g, io::find_camera(f1, g, as_run), as_run));
    }
    as_run.calibration = "";  // "auto": the sample has no calibration/ folder beside its frames
    as_run.unseen_carry_auto = false;  // "auto": false, without a calibration
    EXPECT_EQ(preset, to_json(as_run));
    EXPECT_NEAR(preset["gather_radius"].get<double>(), 5.37, 0.01);  // 256 px x 2.99 m / 142.2 px
    EXPECT_EQ(preset["thickness"], 0.4);  // 0.15 x 2.99 m, at most 0.4 x radius
    EXPECT_NEAR(preset["gather_thickness"].get<double>(), 0.3 * 2.986, 0.002);
    EXPECT_EQ(px.spec.get_string_attribute("hbil:version"), HBIL_VERSION);
    // The writer is hbil; Blender's multilayer marker (in the input) is not carried over.
    EXPECT_EQ(px.spec.get_string_attribute("Software"), "hbil " HBIL_VERSION);
    EXPECT_EQ(px.spec.find_attribute("BlenderMultiChannel"), nullptr);
    const json cam = json::parse(px.spec.get_string_attribute("hbil:camera"));
    EXPECT_EQ(cam["source"], "sidecar frame_000" + std::to_string(frame) + ".camera.json");
    EXPECT_EQ(cam["resolution"], json::array({kSampleW, kSampleH}));
    EXPECT_NEAR(cam["fx"].get<double>(), 20.0 / 36.0 * kSampleW,
                1e-6);  // lens / sensor width * width
    EXPECT_NE(px.spec.find_attribute("worldtocamera"), nullptr);
    EXPECT_NE(px.spec.find_attribute("worldtoNDC"), nullptr);
    EXPECT_EQ(px.spec.get_string_attribute("Camera"), "Camera");
    EXPECT_EQ(px.spec.get_string_attribute("Scene"), "room_poles");
    EXPECT_EQ(px.spec.get_string_attribute("Frame"), std::to_string(frame));
    EXPECT_EQ(px.spec.get_string_attribute("compression"), "rle");
    // Colour layers as half, data layers (ao, bentcone) as float (colour_half = true).
    ASSERT_EQ(px.spec.channelformats.size(), names.size());
    for (size_t c = 0; c < names.size(); ++c) {
      const bool data = names[c].rfind("ao.", 0) == 0 || names[c].rfind("bentcone.", 0) == 0;
      EXPECT_EQ(px.spec.channelformats[c], data ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::HALF)
          << names[c];
    }

    // Values: AO in [0, 1] with real occlusion somewhere; bent normals unit length where
    // the AO is defined; cone cosines in [0, 1].
    double ao_min = 1, ao_max = 0;
    size_t unit = 0;
    for (int y = 0; y < kSampleH; ++y)
      for (int x = 0; x < kSampleW; ++x) {
        const float ao = px.at(x, y, 0), bx = px.at(x, y, 1), by = px.at(x, y, 2),
                    bz = px.at(x, y, 3), w = px.at(x, y, 4);
        ASSERT_TRUE(std::isfinite(ao) && std::isfinite(bx) && std::isfinite(by) &&
                    std::isfinite(bz) && std::isfinite(w))
            << x << "," << y;
        ASSERT_GE(ao, 0.f);
        ASSERT_LE(ao, 1.f);
        ASSERT_GE(w, 0.f);
        ASSERT_LE(w, 1.f);
        ao_min = std::min<double>(ao_min, ao);
        ao_max = std::max<double>(ao_max, ao);
        unit += std::abs(std::sqrt(bx * bx + by * by + bz * bz) - 1.f) < 1e-3f;
      }
    EXPECT_LT(ao_min, 0.5) << "corners and pole feet are occluded";
    EXPECT_GT(ao_max, 0.9) << "open floor is nearly unoccluded";
    EXPECT_GT(unit, size_t(kSampleW * kSampleH) * 9 / 10) << "bent normals are unit vectors";
  }
}

// With either method's SIMD march, and with --overlap.
TEST_F(Cli, ThreadCountDoesNotChangeBytes) {
  for (const std::string method : {"bitmask", "horizon"}) {
    SCOPED_TRACE(method);
    std::vector<std::string> outs;
    // With and without reading each next frame while the previous one is written.
    for (const std::string run :
         {"--threads 1", "--threads 2 --overlap off", "--threads 3", "--threads 2 --overlap on"}) {
      const std::string stem = "out/" + method + "-" + std::to_string(outs.size()) + "_";
      const RunResult r =
          hbil(run_args(test::kRoomPoles + "/frame_####.exr", path(stem + "####.exr"),
                        "--frames 1-3 -q --set method=" + method + " " + run));
      ASSERT_EQ(r.code, 0) << r.err;
      EXPECT_EQ(r.err, "") << "-q prints nothing";
      outs.push_back(path(stem));
    }
    for (const char* frame : {"0001.exr", "0002.exr", "0003.exr"}) {
      const Pixels a = test::read_pixels(outs[0] + frame);
      ASSERT_EQ(a.data.size(), size_t(kSampleW) * kSampleH * kOutputChannels.size());
      const std::string bytes = test::read_text(outs[0] + frame);
      const std::string png = fs::path(frame).replace_extension(".png").string();
      const std::string png_bytes = test::read_text(outs[0] + png);
      for (size_t k = 1; k < outs.size(); ++k) {
        SCOPED_TRACE(outs[k] + frame);
        const Pixels b = test::read_pixels(outs[k] + frame);
        ASSERT_EQ(a.data.size(), b.data.size());
        EXPECT_EQ(std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)), 0);
        EXPECT_TRUE(test::read_text(outs[k] + frame) == bytes) << "files differ";
        EXPECT_TRUE(test::read_text(outs[k] + png) == png_bytes) << "PNGs differ";
      }
    }
  }
}

TEST_F(Cli, SequenceWithoutSidecarsSolvesTheCamera) {
  copy_frame(1, /*sidecar=*/false);
  copy_frame(2, /*sidecar=*/false);
  const RunResult r = hbil(run_args(path("in/frame_####.exr"), path("out/solved_####.exr")));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "camera: solved from Position")) << r.err;
  EXPECT_TRUE(contains(r.err, "2 frames")) << r.err;
  ASSERT_EQ(hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("out/sidecar_####.exr"),
                          "--frames 1-2"))
                .code,
            0);
  for (const char* frame : {"0001.exr", "0002.exr"}) {
    SCOPED_TRACE(frame);
    const Pixels solved = test::read_pixels(path("out/solved_") + frame);
    const Pixels truth = test::read_pixels(path("out/sidecar_") + frame);
    const json cam = json::parse(solved.spec.get_string_attribute("hbil:camera"));
    EXPECT_TRUE(contains(cam["source"].get<std::string>(), "solved from Position")) << cam.dump();
    EXPECT_LT(cam["reprojection_rms_px"].get<double>(), 0.5);
    ASSERT_EQ(solved.data.size(), truth.data.size());
    double se = 0;
    for (int y = 0; y < kSampleH; ++y)
      for (int x = 0; x < kSampleW; ++x) se += std::pow(solved.at(x, y, 0) - truth.at(x, y, 0), 2);
    const double rmse = std::sqrt(se / (kSampleW * kSampleH));
    EXPECT_LT(rmse, kSolvedCameraAoRmse)
        << "AO with the solved camera differs from AO with the true one";
  }
}

// An input with only the geometry passes: "auto" falls back to ao and bentcone, says what it
// left out and why, and writes no display image; naming a colour output instead is an error.
TEST_F(Cli, AutoOutputsOnAnAoOnlyInput) {
  for (int n : {1, 2}) {
    test::copy_exr(sample(n), in_frame(n), {"ViewLayer.DiffCol.", "ViewLayer.DiffDir."});
    fs::copy_file(sample(n, ".camera.json"), in_frame(n, ".camera.json"));
  }
  const RunResult r = hbil(run_args(path("in/frame_####.exr"), path("out/out_####.exr")));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "hbil: outputs: ao, bentcone\n")) << r.err;
  EXPECT_TRUE(contains(r.err, "left out what the input cannot give")) << r.err;
  EXPECT_TRUE(contains(r.err, "missing pass: diffcol")) << r.err;
  const auto files = snapshot(path("out"));
  EXPECT_EQ(files.size(), 2u) << "two EXRs, no PNG without a composite";
  const Pixels px = test::read_pixels(path("out/out_0001.exr"));
  EXPECT_EQ(std::vector<std::string>(px.spec.channelnames.begin(), px.spec.channelnames.end()),
            kAoChannels);
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr"),
                          "--set 'outputs=[\"ao\",\"indirect\"]'"),
                 Exit::missing_pass, {"frame 1", "missing pass: diffcol", "ViewLayer.DiffCol.R"});
}

TEST_F(Cli, NoDisplayWritesOnlyTheExr) {
  const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("out/out_####.exr"),
                                    "--frames 1 --no-display"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(snapshot(path("out")).size(), 1u);
  expect_failure(run_args(test::kRoomPoles + "/frame_####.exr", path("out/out_####.exr"),
                          "--frames 1 --no-display --display-out " + q(path("out/d_####.png"))),
                 Exit::usage, {"--no-display"});
}

// compression and colour_half: the file says what the preset asked for, and half colour
// layers hold the float run's values to half's precision (2^-11 relative above 6.1e-5).
TEST_F(Cli, OutputCompressionAndHalfColourLayers) {
  for (const char* c : {"zip", "none"}) {
    const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr",
                                      path(std::string("out/") + c + "_####.exr"),
                                      std::string("--frames 1 --no-display --set compression=") +
                                          c + " --set colour_half=false"));
    ASSERT_EQ(r.code, 0) << r.err;
    const Pixels px = test::read_pixels(path(std::string("out/") + c + "_0001.exr"));
    EXPECT_EQ(px.spec.get_string_attribute("compression"), c);
    EXPECT_TRUE(px.spec.channelformats.empty() && px.spec.format == OIIO::TypeDesc::FLOAT);
  }
  const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("out/half_####.exr"),
                                    "--frames 1 --no-display"));
  ASSERT_EQ(r.code, 0) << r.err;
  const Pixels full = test::read_pixels(path("out/none_0001.exr"));
  const Pixels half = test::read_pixels(path("out/half_0001.exr"));
  ASSERT_EQ(full.data.size(), half.data.size());
  double worst = 0;
  size_t compared = 0;
  for (size_t k = 0; k < full.data.size(); ++k) {
    const float f = full.data[k], h = half.data[k];
    const size_t c = k % full.spec.nchannels;
    const std::string& name = full.spec.channelnames[c];
    const bool data = name.rfind("ao.", 0) == 0 || name.rfind("bentcone.", 0) == 0;
    if (data) {
      ASSERT_EQ(f, h) << name << ": data layers stay 32-bit";
    } else if (std::fabs(f) > 6.1e-5f) {
      worst = std::max(worst, std::fabs(double(h) - f) / std::fabs(f));
      ++compared;
    }
  }
  EXPECT_GT(compared, full.data.size() / 4);
  EXPECT_LE(worst, std::ldexp(1.0, -11)) << "worst relative error of a half colour value";
  EXPECT_GT(worst, 0) << "the colour layers were not written as half";
}

TEST_F(Cli, InputSpaceFromThePresetAndTheOption) {
  // The preset's input_space is the display transform's source; --input-space overrides it.
  auto source = [&](const std::string& extra) {
    const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr",
                                      path("out/out_####.exr"), "--frames 1 " + extra));
    EXPECT_EQ(r.code, 0) << r.err;
    return r.err;
  };
  EXPECT_TRUE(contains(source(""), "Linear Rec.709 (sRGB) -> display sRGB"));
  EXPECT_TRUE(contains(source("--set input_space=ACEScg"), "ACEScg -> display sRGB"));
  EXPECT_TRUE(contains(source("--set input_space=ACEScg --input-space ACEScct"),
                       "ACEScct -> display sRGB"));
}

// --- Temporal chain ----------------------------------------------------------------------

TEST_F(Cli, PrerollChunkMatchesTheWholeRun) {
  // A farm chunk 6-8 with 4 frames of pre-roll against the whole shot 1-8. Measured RMS
  // differences: ao 0.0056, irradiance 0.0025, composite 0.0014 (without pre-roll: ao 0.04).
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  // RMS difference of one layer over frames 6-8 of two runs, from `hbil compare --json`.
  auto rms_between = [&](const std::string& a, const std::string& b, const std::string& layer) {
    const RunResult r = hbil("compare " + q(a) + " " + q(b) + " --layer " + layer +
                             " --mask none --frames 6-8 --json");
    EXPECT_EQ(r.code, 0) << r.err;
    return json::parse(r.out)["overall"]["rmse"].get<double>();
  };
  auto run = [&](const std::string& out, const std::string& extra) {
    const RunResult r = hbil(run_args(in, path(out + "/f_####.exr"), "--no-display " + extra));
    ASSERT_EQ(r.code, 0) << r.err;
  };
  run("full", "");
  run("chunk", "--frames 6-8 --preroll 4");
  run("cold", "--frames 6-8");
  EXPECT_FALSE(fs::exists(path("chunk/f_0005.exr"))) << "pre-roll frames are not written";
  const std::string full = path("full/f_####.exr"), chunk = path("chunk/f_####.exr");
  EXPECT_LT(rms_between(chunk, full, "ao"), 0.01);
  EXPECT_LT(rms_between(chunk, full, "irradiance"), 0.005);
  EXPECT_LT(rms_between(chunk, full, "composite"), 0.003);
  EXPECT_GT(rms_between(path("cold/f_####.exr"), full, "ao"), 0.015);
}

// radiance_cache_ahead: a chunk reads the frames after its own as the whole run does, and
// gives the whole run's bytes. The sample played backwards, so that what the frames ahead show
// lies outside the earlier frames' view.
TEST_F(Cli, FramesReadAheadMakeAChunkTheWholeRun) {
  for (int n = 1; n <= 8; ++n) {
    const std::string from = test::kRoomPoles + "/frame_000" + std::to_string(9 - n);
    const std::string to = path("in/frame_000" + std::to_string(n));
    fs::create_symlink(from + ".exr", to + ".exr");
    fs::create_symlink(from + ".camera.json", to + ".camera.json");
  }
  const std::string in = path("in/frame_####.exr");
  auto run = [&](const std::string& out, const std::string& extra) {
    const RunResult r = hbil(run_args(in, path(out + "/f_####.exr"),
                                      "--no-display -q --set 'outputs=[\"indirect\"]' " + extra));
    ASSERT_EQ(r.code, 0) << r.err;
  };
  run("whole", "--set radiance_cache_ahead=3");
  run("chunk", "--set radiance_cache_ahead=3 --frames 4-5 --preroll 3");
  run("plain", "");
  for (const char* f : {"f_0004.exr", "f_0005.exr"})
    EXPECT_EQ(test::read_text(path("chunk/") + f), test::read_text(path("whole/") + f)) << f;
  // What lies ahead changes frame 5 (without frames 6-8 on disk, the chunk's frames 4 and 5
  // differ from the whole run's by an RMSE of 3e-4).
  const RunResult r =
      hbil("compare " + q(path("plain/f_####.exr")) + " " + q(path("whole/f_####.exr")) +
           " --layer indirect --mask none --frames 5 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_GT(json::parse(r.out)["overall"]["rmse"].get<double>(), 1e-5);
}

// The frames a chain reads ahead are checked before its first frame: a broken one stops the
// run, naming it, with nothing written. A run of one frame has no chain and opens none.
TEST_F(Cli, FramesAheadAreCheckedOnlyWhenAChainReadsThem) {
  link_frame(1);
  link_frame(2);
  test::write_text(in_frame(3), "not an EXR\n");
  const std::string in = path("in/frame_####.exr");
  const std::string ahead = "--no-display -q --set radiance_cache_ahead=2 ";
  expect_failure(run_args(in, path("out/out_####.exr"), ahead + "--frames 1-2"), Exit::input,
                 {"frame_0003.exr"});
  const RunResult one = hbil(run_args(in, path("one/f_####.exr"), ahead + "--frames 1"));
  EXPECT_EQ(one.code, 0) << one.err;
  EXPECT_TRUE(fs::exists(path("one/f_0001.exr")));
}

TEST_F(Cli, CutFramesAreLoggedAndBadListsRefused) {
  const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("out/f_####.exr"),
                                    "--no-display --frames 1-4 --cut-frames 3"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "frame 3: cut (given), history dropped")) << r.err;
  EXPECT_FALSE(contains(r.err, "frame 2: cut")) << r.err;
  expect_failure(
      run_args(test::kRoomPoles + "/frame_####.exr", path("out2/f_####.exr"), "--cut-frames 3,x"),
      Exit::usage, {"--cut-frames", "\"x\""});
}

TEST_F(Cli, HardCutIsDetected) {
  const std::string in = std::string(HBIL_SOURCE_DIR) + "/samples/room_cut/frame_####.exr";
  const RunResult r = hbil(
      run_args(in, path("cut/f_####.exr"), "--no-display --frames 2-5 --set 'outputs=[\"ao\"]'"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "frame 4: cut (camera moved")) << r.err;
  EXPECT_FALSE(contains(r.err, "frame 3: cut")) << r.err;
  EXPECT_FALSE(contains(r.err, "frame 5: cut")) << r.err;
}

TEST_F(Cli, AccumulationReducesFlickerOnAStaticCamera) {
  // samples/room_static: identical Cycles frames; the slices turn every frame, so each
  // frame's own estimate changes and only the accumulation keeps the output still.
  // Measured composite RMS change between frames 3 and 4: 0.0013 accumulated, 0.0059 not.
  const std::string in = std::string(HBIL_SOURCE_DIR) + "/samples/room_static/frame_####.exr";
  auto change = [&](const std::string& name, const std::string& extra) {
    const RunResult r =
        hbil(run_args(in, path(name + "/f_####.exr"), "--no-display --frames 1-4 " + extra));
    EXPECT_EQ(r.code, 0) << r.err;
    const RunResult c = hbil("compare " + q(path(name + "/f_0004.exr")) + " " +
                             q(path(name + "/f_0003.exr")) + " --layer composite --json");
    EXPECT_EQ(c.code, 0) << c.err;
    return json::parse(c.out)["overall"]["rmse"].get<double>();
  };
  const double accumulated = change("acc", ""), single = change("one", "--set history_max=1");
  EXPECT_LT(accumulated, 0.5 * single) << accumulated << " vs " << single;
}

// --- Failures: exit code, a message naming the file and frame, nothing written --------

TEST_F(Cli, MissingPassFailsWithoutOutput) {
  copy_frame(1);
  test::copy_exr(sample(2), in_frame(2), {"ViewLayer.Normal."});
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::missing_pass,
                 {"hbil: error: ", "frame 2", in_frame(2), "ViewLayer.Normal.X"}, {});
}

// A frame's own render stands in for its panorama (it has Position, DiffCol, DiffDir, Emit):
// what it shows, also beyond the gather's reach, lights the empty directions, so indirect
// light grows (with no fill, unseen_radiance 0, so that only the panorama lights them); a
// panorama without Position is a missing pass naming its file.
TEST_F(Cli, PanoramaLightsTheEmptyDirectionsAndNeedsItsPasses) {
  copy_frame(1);
  const std::string set = "--set 'outputs=[\"indirect\"]' --set unseen_radiance=0 --no-display ";
  ASSERT_EQ(hbil(run_args(in_frame(1), path("out/a.exr"), set)).code, 0);
  const RunResult r = hbil(run_args(in_frame(1), path("out/b.exr"),
                                    set + "--set panorama=" + q(path("in/frame_####.exr"))));
  ASSERT_EQ(r.code, 0) << r.err;
  const Pixels a = test::read_pixels(path("out/a.exr")), b = test::read_pixels(path("out/b.exr"));
  const int c = a.channel("indirect.G");
  ASSERT_GE(c, 0);
  double sa = 0, sb = 0;
  for (int y = 0; y < a.spec.height; ++y)
    for (int x = 0; x < a.spec.width; ++x) sa += a.at(x, y, c), sb += b.at(x, y, c);
  EXPECT_GT(sb, sa * 1.05);
  test::copy_exr(sample(1), path("in/pano_0001.exr"), {"ViewLayer.Position."});
  expect_failure(run_args(in_frame(1), path("out/c.exr"),
                          set + "--set panorama=" + q(path("in/pano_####.exr"))),
                 Exit::missing_pass,
                 {"frame 1", path("in/pano_0001.exr"), "panorama", "ViewLayer.Position.X"}, {});
}

TEST_F(Cli, NonFiniteDepthFailsKeepingTheFramesBefore) {
  copy_frame(1);
  test::copy_exr(sample(2), in_frame(2), {}, [](Pixels& p) {
    p.at(10, 20, p.channel("ViewLayer.Depth.Z")) = std::numeric_limits<float>::quiet_NaN();
  });
  fs::copy_file(sample(2, ".camera.json"), in_frame(2, ".camera.json"));
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::bad_data,
                 {"frame 2", in_frame(2), "ViewLayer.Depth.Z", "non-finite", "(10, 20)",
                  "hbil: frame 1 was written (1 of 2); the others were not"},
                 {1});
}

// --log-json: one JSON object per line, appended: the run's start, a line per frame once its
// files are in place (stage times, camera, cut, history), and the end with the exit status.
std::vector<nlohmann::json> log_lines(const std::string& file) {
  std::vector<nlohmann::json> v;
  std::istringstream in(test::read_text(file));
  for (std::string line; std::getline(in, line);) v.push_back(nlohmann::json::parse(line));
  return v;
}

TEST_F(Cli, LogJsonRecordsEachFrameAndTheEnd) {
  const std::string log = path("logs/run.jsonl");  // its folder is created
  const RunResult r = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("out/f_####.exr"),
                                    "--frames 1-3 --cut-frames 3 -q --log-json " + q(log)));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto v = log_lines(log);
  ASSERT_EQ(v.size(), 5u) << test::read_text(log);
  EXPECT_EQ(v[0]["event"], "start");
  EXPECT_EQ(v[0]["frames"], nlohmann::json::array({1, 2, 3}));
  EXPECT_EQ(v[0]["resolution"], nlohmann::json::array({256, 144}));
  EXPECT_EQ(v[0]["outputs"],
            nlohmann::json::array({"ao", "bentcone", "irradiance", "indirect", "composite"}));
  EXPECT_EQ(v[0]["input"], test::kRoomPoles + "/frame_####.exr");
  for (int f = 1; f <= 3; ++f) {
    const nlohmann::json& e = v[size_t(f)];
    EXPECT_EQ(e["event"], "frame");
    EXPECT_EQ(e["frame"], f);
    EXPECT_EQ(e["index"], f);
    EXPECT_EQ(e["of"], 3);
    for (const char* k : {"read_ms", "camera_ms", "compute_ms", "write_ms"})
      EXPECT_GE(e[k].get<double>(), 0.0) << k;
    EXPECT_GT(e["compute_ms"].get<double>(), 0.0);
    EXPECT_EQ(e["camera"], "sidecar frame_000" + std::to_string(f) + ".camera.json");
    const std::string stem = path("out/f_000" + std::to_string(f));
    EXPECT_EQ(e["files"], nlohmann::json::array({stem + ".exr", stem + ".png"}));
    for (const auto& file : e["files"]) EXPECT_TRUE(fs::exists(file.get<std::string>()));
  }
  // Frame 1 has no history, frame 2 reprojects frame 1's, frame 3 is a given cut.
  EXPECT_TRUE(v[1]["history"].is_null() && v[1]["cut"].is_null());
  EXPECT_GT(v[2]["history"].get<double>(), 0.9);
  EXPECT_LE(v[2]["history"].get<double>(), 1.0);
  EXPECT_EQ(v[2]["reprojection"], "vector");
  EXPECT_EQ(v[3]["cut"], "given");
  EXPECT_TRUE(v[3]["history"].is_null());
  EXPECT_EQ(v[4]["event"], "end");
  EXPECT_EQ(v[4]["exit"], 0);
  EXPECT_EQ(v[4]["written"], 3);
  EXPECT_FALSE(v[4].contains("error"));
  // The rate after the first frame: the 2 intervals between the 3 frames finished, which the
  // whole run (its start and the first frame's reading and computing too) outlasts.
  const double after_first = v[4]["seconds_per_frame_after_first"].get<double>();
  EXPECT_GT(after_first, 0.0);
  EXPECT_LT(2 * after_first, v[4]["seconds"].get<double>());
  // A single frame has no such rate: null in the log, and not in the summary.
  const RunResult one =
      hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("one/f_####.exr"),
                    "--frames 2 --no-display --log-json " + q(path("one.jsonl"))));
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_TRUE(log_lines(path("one.jsonl")).back()["seconds_per_frame_after_first"].is_null());
  EXPECT_TRUE(contains(one.err, "hbil: 1 frame, ")) << one.err;
  EXPECT_FALSE(contains(one.err, "after the first")) << one.err;
  const RunResult two = hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("two/f_####.exr"),
                                      "--frames 2-3 --no-display"));
  ASSERT_EQ(two.code, 0) << two.err;
  EXPECT_TRUE(contains(two.err, " s a frame after the first")) << two.err;

  // A second run appends; one that fails logs its exit status and what it wrote, here frame 1.
  copy_frame(1);
  test::copy_exr(sample(2), in_frame(2), {}, [](Pixels& p) {
    p.at(10, 20, p.channel("ViewLayer.Depth.Z")) = std::numeric_limits<float>::quiet_NaN();
  });
  fs::copy_file(sample(2, ".camera.json"), in_frame(2, ".camera.json"));
  expect_failure(
      run_args(path("in/frame_####.exr"), path("out/out_####.exr"), "--log-json " + q(log)),
      Exit::bad_data, {"frame 2", "non-finite"}, {1});
  const auto w = log_lines(log);
  ASSERT_EQ(w.size(), 5u + 3u) << test::read_text(log);
  EXPECT_EQ(w[5]["event"], "start");
  EXPECT_EQ(w[6]["event"], "frame");
  EXPECT_EQ(w[6]["frame"], 1);
  EXPECT_EQ(w[7]["event"], "end");
  EXPECT_EQ(w[7]["exit"], int(Exit::bad_data));
  EXPECT_EQ(w[7]["written"], 1);
  EXPECT_TRUE(contains(w[7]["error"].get<std::string>(), "non-finite")) << w[7];

  // A log that cannot be opened is an output error before anything runs.
  test::write_text(path("blocker"), "a file, not a folder\n");
  expect_failure(run_args(test::kRoomPoles + "/frame_####.exr", path("out/out_####.exr"),
                          "--frames 1 --log-json " + q(path("blocker/run.jsonl"))),
                 Exit::output, {"--log-json", path("blocker/run.jsonl")});
}

TEST_F(Cli, NegativeDepthFailsKeepingTheFramesBefore) {
  copy_frame(1);
  test::copy_exr(sample(2), in_frame(2), {},
                 [](Pixels& p) { p.at(200, 100, p.channel("ViewLayer.Depth.Z")) = -2.5f; });
  fs::copy_file(sample(2, ".camera.json"), in_frame(2, ".camera.json"));
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::bad_data,
                 {"frame 2", in_frame(2), "ViewLayer.Depth.Z", "negative depth", "(200, 100)",
                  "-2.5", "hbil: frame 1 was written (1 of 2)"},
                 {1});
}

TEST_F(Cli, ResolutionChangeFailsWithoutOutput) {
  copy_frame(1);
  test::crop_exr(sample(2), in_frame(2), 128, 72);
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::bad_data,
                 {"frame 2", in_frame(2), "128x72", "256x144", in_frame(1)}, {});
}

// SIGTERM (what a farm's scheduler sends) in the middle of a run: the frames finished before
// it stay, whole; the temporaries in flight are removed; the process ends by the signal (the
// shell's 143) after one line saying which frames were written.
TEST_F(Cli, SigtermKeepsFinishedFramesAndRemovesTemporaries) {
  // Slow enough settings (about a second a frame here) that the signal arrives mid-run.
  const std::string cmd = "exec " + test::shell_quote(HBIL_BINARY) + " " +
                          run_args(test::kRoomPoles + "/frame_####.exr", path("out/out_####.exr"),
                                   "-q --set steps=96 --set gather_steps=96 --set slices=6 "
                                   "--log-json " +
                                       q(path("run.jsonl"))) +
                          " 2> " + q(path("err.txt")) + " < /dev/null";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Waits for frame 1 to be in place, then for a temporary of a later frame.
  const auto t0 = std::chrono::steady_clock::now();
  auto waited = [&] { return std::chrono::steady_clock::now() - t0 > std::chrono::seconds(120); };
  while (!fs::exists(path("out/out_0001.exr")) && !waited())
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  while (test::files_containing(path("out"), ".hbil-tmp").empty() && !waited())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_FALSE(waited()) << "the run never wrote frame 1 and a temporary of frame 2";
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string err = test::read_text(path("err.txt"));
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit " << WEXITSTATUS(status) << ": " << err;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_TRUE(contains(err, "hbil: interrupted (signal 15): ")) << err;
  EXPECT_TRUE(test::files_containing(dir.path(), ".hbil-tmp").empty())
      << "a temporary outlived the signal";
  // Every frame in place is whole (the EXR with all its layers, and its PNG), and the line
  // names as many frames as there are.
  int whole = 0;
  for (int f = 1; f <= 8; ++f) {
    const std::string exr = path("out/out_000" + std::to_string(f) + ".exr");
    if (!fs::exists(exr)) continue;
    ++whole;
    EXPECT_EQ(test::read_pixels(exr).spec.channelnames, kOutputChannels) << exr;
    EXPECT_TRUE(fs::exists(path("out/out_000" + std::to_string(f) + ".png"))) << f;
  }
  EXPECT_GE(whole, 1);
  EXPECT_LT(whole, 8) << "the signal came after the run: it proves nothing";
  EXPECT_TRUE(contains(err, whole == 1
                                ? "1 frame was written (frame 1)"
                                : std::to_string(whole) + " frames were written (frames 1 to " +
                                      std::to_string(whole) + ")"))
      << err;
  // The run log: a line per frame in place, then the interrupted end (143 = 128 + SIGTERM).
  const auto v = log_lines(path("run.jsonl"));
  ASSERT_EQ(v.size(), size_t(whole) + 2) << test::read_text(path("run.jsonl"));
  EXPECT_EQ(v.front()["event"], "start");
  for (int f = 1; f <= whole; ++f) EXPECT_EQ(v[size_t(f)]["frame"], f);
  EXPECT_EQ(v.back()["event"], "end");
  EXPECT_EQ(v.back()["exit"], 143);
  EXPECT_EQ(v.back()["signal"], SIGTERM);
  EXPECT_EQ(v.back()["written"], whole);
  EXPECT_EQ(v.back()["error"], "interrupted");
}

// A run killed outright (SIGKILL) leaves its temporaries; the next run into the folder
// removes those of processes of this host that are gone, and no other file.
TEST_F(Cli, StaleTemporariesOfDeadProcessesAreRemoved) {
  char host[256] = {};
  ASSERT_EQ(gethostname(host, sizeof host - 1), 0);
  const pid_t dead = fork();  // a process that has ended and been reaped
  ASSERT_GE(dead, 0);
  if (dead == 0) _exit(0);
  ASSERT_EQ(waitpid(dead, nullptr, 0), dead);
  const std::string h = host, d = std::to_string(dead), me = std::to_string(getpid());
  const std::vector<std::string> stale = {".out_0001.hbil-tmp-" + h + "-" + d + "-0.exr",
                                          ".out_0001.hbil-tmp-display-" + h + "-" + d + "-1.png"};
  const std::vector<std::string> kept = {
      ".out_0001.hbil-tmp-" + h + "-" + me + "-0.exr",  // a process that runs
      ".out_0001.hbil-tmp-other-node-" + d + "-0.exr",  // another host's
      ".out_0001.hbil-tmp-" + d + "-0.exr",             // no host in the name
      "out_0001.hbil-tmp-" + h + "-" + d + "-0.exr",    // not hidden
      ".notes.txt"};
  for (const auto& n : stale) test::write_text(path("out/" + n), "killed\n");
  for (const auto& n : kept) test::write_text(path("out/" + n), "other\n");
  const RunResult r =
      hbil(run_args(test::kRoomPoles + "/frame_####.exr", path("out/out_####.exr"), "--frames 1"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "hbil: removed 2 temporary files left by a run that was killed"))
      << r.err;
  for (const auto& n : stale) EXPECT_FALSE(fs::exists(path("out/" + n))) << n;
  for (const auto& n : kept) EXPECT_TRUE(fs::exists(path("out/" + n))) << n;
}

// The display image is written beside the EXR: when it cannot be, neither stays.
TEST_F(Cli, UnwritableDisplayImageFailsWithoutOutput) {
  copy_frame(1);
  copy_frame(2);
  test::write_text(path("blocker"), "a file where the display folder would be\n");
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr"),
                          "--frames 1-2 --display-out " + q(path("blocker/d_####.png"))),
                 Exit::output, {path("blocker/d_0001.png"), "cannot create folder"});
}

TEST_F(Cli, MissingInputFrameFailsWithoutOutput) {
  copy_frame(1);
  copy_frame(2);
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr"), "--frames 1-3"),
                 Exit::input, {"frame 3", in_frame(3), "not found"});
}

// Every input of --frames is looked at before the first frame is computed: the error is the
// only line, and frames 1 and 2 were not computed first.
TEST_F(Cli, MissingOrUnreadableFrameFailsBeforeAnyFrameIsComputed) {
  for (int n : {1, 2, 4}) link_frame(n);
  RunResult r =
      expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr"), "--frames 1-4"),
                     Exit::input, {"hbil: error: frame 3 (" + in_frame(3) + "): file not found"});
  EXPECT_FALSE(contains(r.err, "hbil: frame 1")) << "a frame was computed first:\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A frame whose header cannot be read, after the first.
  test::write_text(in_frame(3), "not an EXR\n");
  r = expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr"), "--frames 1-4"),
                     Exit::input, {"frame 3 (" + in_frame(3) + "): cannot read"});
  EXPECT_FALSE(contains(r.err, "hbil: frame 1")) << r.err;
  // The same for pre-roll frames, and without --frames.
  r = expect_failure(
      run_args(path("in/frame_####.exr"), path("out/out_####.exr"), "--frames 4 --preroll 3"),
      Exit::input, {"frame 3 (" + in_frame(3) + "): cannot read"});
  EXPECT_FALSE(contains(r.err, "pre-roll")) << r.err;
  r = expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::input,
                     {"frame 3 (" + in_frame(3) + "): cannot read"});
  EXPECT_FALSE(contains(r.err, "hbil: frame 1")) << r.err;
}

// Without --frames a missing frame is a gap: the frame after it starts without history
// (history.Y = 1 on every pixel) and the log says why; frames rendered on twos are no gap.
TEST_F(Cli, GapInTheSequenceDropsTheHistory) {
  for (int n : {1, 2, 4}) link_frame(n);
  const std::string outputs = "--no-display --set 'outputs=[\"ao\",\"history\"]'";
  const RunResult r = hbil(run_args(path("in/frame_####.exr"), path("out/gap_####.exr"), outputs));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "hbil: frame 4: cut (frame 3 missing), history dropped")) << r.err;
  EXPECT_FALSE(contains(r.err, "frame 2: cut")) << r.err;
  auto history = [&](const std::string& file) {
    const Pixels px = test::read_pixels(path(file));
    const int c = px.channel("history.Y");
    EXPECT_GE(c, 0) << file;
    double max = 0, sum = 0;
    size_t n = 0;
    for (int y = 0; c >= 0 && y < px.spec.height; ++y)
      for (int x = 0; x < px.spec.width; ++x)
        if (const float h = px.at(x, y, c); h > 0) max = std::max<double>(max, h), sum += h, ++n;
    return std::pair{max, n ? sum / double(n) : 0.0};
  };
  EXPECT_GT(history("out/gap_0002.exr").second, 1.8) << "frame 2 accumulates frame 1";
  EXPECT_EQ(history("out/gap_0004.exr").first, 1.0) << "frame 4 took no history";

  // Frames 1, 3, 5 only: the sequence's step is 2, the history is kept.
  fs::remove_all(path("in"));
  fs::create_directories(path("in"));
  for (int n : {1, 3, 5}) link_frame(n);
  const RunResult twos =
      hbil(run_args(path("in/frame_####.exr"), path("out/twos_####.exr"), outputs));
  ASSERT_EQ(twos.code, 0) << twos.err;
  EXPECT_FALSE(contains(twos.err, "missing")) << twos.err;
  EXPECT_GT(history("out/twos_0005.exr").second, 2.0) << "frame 5 accumulates 1 and 3";
}

// oiiotool's frame lists: a step keeps the history (the sequence's step is the list's), a
// list with a hole drops it at the hole, negative frames are frames.
TEST_F(Cli, FrameListsInOiiotoolSyntax) {
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const RunResult twos = hbil(run_args(
      in, path("out/x_####.exr"), "--no-display --frames 1-5x2 --log-json " + q(path("x.jsonl"))));
  ASSERT_EQ(twos.code, 0) << twos.err;
  EXPECT_FALSE(contains(twos.err, "missing")) << twos.err;
  EXPECT_EQ(log_lines(path("x.jsonl")).front()["frames"], nlohmann::json::array({1, 3, 5}));
  for (int f : {1, 3, 5}) EXPECT_TRUE(fs::exists(path("out/x_000" + std::to_string(f) + ".exr")));
  for (int f : {2, 4}) EXPECT_FALSE(fs::exists(path("out/x_000" + std::to_string(f) + ".exr")));

  const RunResult list = hbil(run_args(in, path("out/l_####.exr"), "--no-display --frames 1,3-4"));
  ASSERT_EQ(list.code, 0) << list.err;
  EXPECT_TRUE(contains(list.err, "hbil: frame 3: cut (frame 2 missing), history dropped"))
      << list.err;
  EXPECT_FALSE(fs::exists(path("out/l_0002.exr")));

  // '@' pads as oiiotool's does; frame -1 is a frame of the pattern.
  fs::create_symlink(sample(1), path("in/neg_-001.exr"));
  fs::create_symlink(sample(1, ".camera.json"), path("in/neg_-001.camera.json"));
  const RunResult neg =
      hbil(run_args(path("in/neg_@@@@.exr"), path("out/n_@@@@.exr"), "--no-display --frames -1"));
  ASSERT_EQ(neg.code, 0) << neg.err;
  EXPECT_TRUE(fs::exists(path("out/n_-001.exr")));
  expect_failure(run_args(in, path("out/out_####.exr"), "--frames 1-4x0"), Exit::usage,
                 {"--frames: \"1-4x0\"", "step", "1-100x2"});
}

// --skip-existing: a resumed run leaves the frames this job made complete, makes the others
// with the bytes an uninterrupted run gives them, and redoes a frame that is cut short, made
// by other settings, or made from an input that changed since.
TEST_F(Cli, SkipExistingResumesWithTheBytesOfAnUninterruptedRun) {
  for (int n = 1; n <= 4; ++n) copy_frame(n);
  const std::string in = path("in/frame_####.exr");
  ASSERT_EQ(hbil(run_args(in, path("whole/f_####.exr"), "-q")).code, 0);
  const auto whole = snapshot(path("whole"));
  ASSERT_EQ(whole.size(), 8u);  // EXR and PNG of 4 frames

  // Killed after frame 2: frame 3's EXR and frame 4's PNG are missing, frame 2's EXR is cut
  // short; frame 1 is in place, with a time stamp that must not change.
  fs::copy(path("whole"), path("resumed"));
  fs::remove(path("resumed/f_0003.exr"));
  fs::remove(path("resumed/f_0004.png"));
  const std::string f2 = path("resumed/f_0002.exr");
  fs::resize_file(f2, fs::file_size(f2) / 2);
  const auto stamp = fs::last_write_time(path("resumed/f_0001.exr"));
  const std::string log = path("resume.jsonl");
  const RunResult r =
      hbil(run_args(in, path("resumed/f_####.exr"), "--skip-existing --log-json " + q(log)));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "skip-existing: frame 1 done by this job, not written again"))
      << r.err;
  EXPECT_TRUE(contains(r.err, "frame 1 (done, computed for the history)")) << r.err;
  EXPECT_EQ(snapshot(path("resumed")), whole) << "a resumed run made other bytes";
  EXPECT_EQ(fs::last_write_time(path("resumed/f_0001.exr")), stamp) << "frame 1 was written again";
  auto v = log_lines(log);
  ASSERT_GE(v.size(), 3u);
  EXPECT_EQ(v[1]["event"], "skip");
  EXPECT_EQ(v[1]["frames"], nlohmann::json::array({1}));
  EXPECT_EQ(v.back()["written"], 3);
  EXPECT_EQ(v.back()["skipped"], 1);

  // Everything done: nothing is computed or written.
  const RunResult again = hbil(run_args(in, path("resumed/f_####.exr"), "--skip-existing"));
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_TRUE(contains(again.err, "frames 1-4 done by this job")) << again.err;
  EXPECT_FALSE(contains(again.err, "computed for the history")) << again.err;
  EXPECT_EQ(snapshot(path("resumed")), whole);

  // Other settings: every frame is made again.
  const RunResult other =
      hbil(run_args(in, path("resumed/f_####.exr"), "--skip-existing --set steps=6"));
  ASSERT_EQ(other.code, 0) << other.err;
  EXPECT_TRUE(contains(other.err, "no frame is done yet")) << other.err;
  EXPECT_TRUE(contains(other.err, "made by other settings or from other inputs")) << other.err;
  EXPECT_NE(snapshot(path("resumed")), whole);

  // Back to the first settings, then frame 3's input changes: frames 3 and 4 (whose history
  // it shapes) are made again, 1 and 2 are not.
  ASSERT_EQ(hbil(run_args(in, path("resumed/f_####.exr"), "-q")).code, 0);
  fs::last_write_time(in_frame(3), fs::last_write_time(in_frame(3)) + std::chrono::seconds(5));
  const RunResult changed = hbil(run_args(in, path("resumed/f_####.exr"), "--skip-existing"));
  ASSERT_EQ(changed.code, 0) << changed.err;
  EXPECT_TRUE(contains(changed.err, "frames 1-2 done by this job")) << changed.err;

  // Without a temporal chain the done frames are not computed.
  const std::string flat = "--set temporal=false --no-display ";
  ASSERT_EQ(hbil(run_args(in, path("flat/f_####.exr"), flat + "-q")).code, 0);
  fs::remove(path("flat/f_0002.exr"));
  const RunResult f = hbil(run_args(in, path("flat/f_####.exr"), flat + "--skip-existing"));
  ASSERT_EQ(f.code, 0) << f.err;
  EXPECT_TRUE(contains(f.err, "frames 1, 3-4 done by this job")) << f.err;
  EXPECT_TRUE(contains(f.err, "hbil: frame 2 (2/4)")) << f.err;
  EXPECT_FALSE(contains(f.err, "computed for the history")) << f.err;
}

// A zero-length normal on geometry is taken as background: the run succeeds, every output
// is finite, and one warning per frame gives the count, the first pixel and the file.
TEST_F(Cli, ZeroLengthNormalsWarnAndAreBackground) {
  test::copy_exr(sample(1), in_frame(1), {}, [](Pixels& p) {
    const int n = p.channel("ViewLayer.Normal.X"), d = p.channel("ViewLayer.Depth.Z");
    for (int y = 50; y < 53; ++y)
      for (int x = 100; x < 104; ++x) {
        ASSERT_LT(p.at(x, y, d), 1e9f) << "the block must be geometry";
        for (int c = 0; c < 3; ++c) p.at(x, y, n + c) = 0.f;
      }
  });
  fs::copy_file(sample(1, ".camera.json"), in_frame(1, ".camera.json"));
  const RunResult r = hbil(run_args(in_frame(1), path("out/z_0001.exr"), "-q --no-display"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "hbil: warning: frame 1 (" + in_frame(1) +
                       "): 12 pixels with a zero-length normal, the first at (100, 50), taken as "
                       "background\n")
      << "printed once, with --quiet too";
  const Pixels px = test::read_pixels(path("out/z_0001.exr"));
  ASSERT_EQ(px.spec.width, kSampleW);
  for (float v : px.data) ASSERT_TRUE(std::isfinite(v));
  // As background: AO 1 in the block.
  EXPECT_EQ(px.at(101, 51, px.channel("ao.Y")), 1.f);
  // The sample itself has none.
  const RunResult clean = hbil(run_args(sample(1), path("out/c_0001.exr"), "-q --no-display"));
  ASSERT_EQ(clean.code, 0) << clean.err;
  EXPECT_EQ(clean.err, "");
}

TEST_F(Cli, NegativeCountsAreUsageErrorsWithAPlainMessage) {
  copy_frame(1);
  RunResult r =
      expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--threads -1"), Exit::usage,
                     {"--threads: must be 0 (all cores) or a positive count, got \"-1\""});
  EXPECT_LT(r.err.size(), 300u) << r.err;
  r = expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--threads 2.5"), Exit::usage,
                     {"--threads: must be 0 (all cores) or a positive count"});
  r = expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr"), "--preroll -2"),
                     Exit::usage, {"--preroll: must be 0 or a positive number of frames"});
  EXPECT_LT(r.err.size(), 300u) << r.err;
  r = expect_failure(
      "bench " + q(in_frame(1)) + " -o " + q(path("out/b")) + " --ref ao=x.exr:AO --threads -1",
      Exit::usage, {"--threads: must be 0 (all cores) or a positive count"});
  const std::string bench =
      "bench " + q(in_frame(1)) + " -o " + q(path("out/b")) + " --ref ao=" + q(in_frame(1)) + ":AO";
  r = expect_failure(bench + " --runs 0", Exit::usage,
                     {"--runs: must be a positive number of runs, got \"0\""});
  EXPECT_LT(r.err.size(), 300u) << r.err;
  const std::string tune = "tune " + q(in_frame(1)) + " -o " + q(path("out/t.json")) +
                           " --ref ao=" + q(in_frame(1)) + ":AO";
  r = expect_failure(tune + " --budget -1", Exit::usage,
                     {"--budget: must be a number of seconds >= 0, got \"-1\""});
  EXPECT_LT(r.err.size(), 300u) << r.err;
  r = expect_failure(tune + " --tolerance nan", Exit::usage,
                     {"--tolerance: must be a number of decibels >= 0"});
  EXPECT_FALSE(fs::exists(path("out/b")));
  EXPECT_FALSE(fs::exists(path("out/t.json")));
}

// A header that claims more pixels than its file can hold: exit 3 naming the file, from
// run and from info, before anything is allocated from it.
TEST_F(Cli, HeaderLargerThanItsFileIsAnInputError) {
  test::patch_data_window(sample(1), in_frame(1), 12000, 12000);
  fs::copy_file(sample(1, ".camera.json"), in_frame(1, ".camera.json"));
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr")), Exit::input,
                 {"hbil: error: frame 1 (" + in_frame(1) + "): the header claims 12000x12000",
                  "header is damaged"});
  RunResult r = hbil("info " + q(in_frame(1)));
  EXPECT_EQ(r.code, int(Exit::input)) << r.err;
  EXPECT_TRUE(contains(r.err, in_frame(1) + "): the header claims 12000x12000")) << r.err;
  test::patch_data_window(sample(1), in_frame(1), 200000, 200000);
  r = hbil("info " + q(in_frame(1)));
  EXPECT_EQ(r.code, int(Exit::input)) << r.err;
  EXPECT_TRUE(contains(r.err, in_frame(1) + "): the header claims 200000x200000")) << r.err;
  EXPECT_FALSE(contains(r.err, "bad_alloc")) << r.err;
}

TEST_F(Cli, NoCameraFailsWithoutOutput) {
  test::copy_exr(sample(1), in_frame(1), {"ViewLayer.Position."});
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr")), Exit::camera,
                 {"frame 1", in_frame(1), "no camera", in_frame(1, ".camera.json")});
}

TEST_F(Cli, UnknownPresetKeyIsExit7) {
  copy_frame(1);
  test::write_text(path("bad_preset.json"), R"({"radius": 0.5, "radiuss": 2})");
  expect_failure(
      run_args(in_frame(1), path("out/out_0001.exr"), "--preset " + q(path("bad_preset.json"))),
      Exit::preset, {path("bad_preset.json"), "unknown key 'radiuss'"});
  test::write_text(path("broken.json"), R"({"radius": )");
  expect_failure(
      run_args(in_frame(1), path("out/out_0001.exr"), "--preset " + q(path("broken.json"))),
      Exit::preset, {path("broken.json"), "not valid JSON"});
}

TEST_F(Cli, MissingOrUnreadablePresetIsExit7) {
  copy_frame(1);
  expect_failure(
      run_args(in_frame(1), path("out/out_0001.exr"), "--preset " + q(path("none.json"))),
      Exit::preset, {"--preset " + path("none.json") + ": file not found"});
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--preset " + q(path("in"))),
                 Exit::preset, {"--preset " + path("in") + ": is a folder"});
  const RunResult r = hbil("preset --dump --preset " + q(path("none.json")));
  EXPECT_EQ(r.code, int(Exit::preset)) << r.err;
  EXPECT_TRUE(contains(r.err, path("none.json"))) << r.err;
}

TEST_F(Cli, BadSetIsExit7) {
  copy_frame(1);
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--set slices=0"), Exit::preset,
                 {"--set slices=0", "'slices'", "[1, 64]"});
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--set nosuchkey=1"), Exit::preset,
                 {"unknown key 'nosuchkey'"});
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--radius -1"), Exit::preset,
                 {"'radius'"});
}

TEST_F(Cli, UnknownOptionIsUsageError) {
  copy_frame(1);
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--bogus"), Exit::usage,
                 {"--bogus"});
  expect_failure("frobnicate", Exit::usage, {"subcommand"});
  expect_failure(run_args(in_frame(1), path("out/out_0001.exr"), "--frames 2-1"), Exit::usage,
                 {"--frames"});
}

TEST_F(Cli, OutputEqualToInputIsUsageError) {
  copy_frame(1);
  copy_frame(2);
  const auto before = snapshot(path("in"));
  expect_failure(run_args(in_frame(1), in_frame(1)), Exit::usage,
                 {in_frame(1), "overwrite its own input"});
  expect_failure(run_args(path("in/frame_####.exr"), path("in/frame_%04d.exr")), Exit::usage,
                 {"overwrite its own input"});
  EXPECT_EQ(snapshot(path("in")), before);
}

TEST_F(Cli, UnwritableOutputFolderIsExit8) {
  copy_frame(1);
  test::write_text(path("out/blocker"), "a regular file where a folder should be\n");
  expect_failure(run_args(in_frame(1), path("out/blocker/out_0001.exr")), Exit::output,
                 {path("out/blocker")});
  EXPECT_TRUE(test::files_containing(dir.path(), ".hbil-tmp").empty());
}

// --- info, compare, preset ----------------------------------------------------------

// Every --help ends with the exit codes and where the manual is.
TEST_F(Cli, HelpNamesTheManualAndTheExitCodes) {
  for (const char* cmd : {"--help", "run --help", "bench --help", "info --help"}) {
    const RunResult r = hbil(cmd);
    EXPECT_EQ(r.code, 0) << cmd << r.err;
    EXPECT_TRUE(contains(r.out, "Exit codes: 0 done, 1 internal error, 2 usage")) << cmd << r.out;
    EXPECT_TRUE(contains(r.out, "8 output cannot be written")) << cmd << r.out;
    EXPECT_TRUE(contains(r.out, "man hbil")) << cmd << r.out;
  }
}

TEST_F(Cli, InfoListsPassesCameraAndOutputs) {
  const RunResult r = hbil("info " + q(sample(1)));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "resolution: 256x144")) << r.out;
  EXPECT_TRUE(contains(r.out, "view layer: ViewLayer")) << r.out;
  EXPECT_TRUE(contains(r.out, "ViewLayer.Depth: Z")) << r.out;
  EXPECT_TRUE(contains(r.out, "depth: ViewLayer.Depth.Z")) << r.out;
  EXPECT_TRUE(contains(r.out, "camera: sidecar frame_0001.camera.json")) << r.out;
  EXPECT_TRUE(contains(r.out, "ao: yes")) << r.out;
  EXPECT_TRUE(contains(r.out, "bentcone: yes")) << r.out;
  // No environment set: no far field, whatever the passes.
  EXPECT_TRUE(contains(r.out, "farfield: no: needs an environment")) << r.out;
  const RunResult env = hbil("info " + q(sample(1)) + " --set 'environment=\"rgb:1,1,1\"'");
  ASSERT_EQ(env.code, 0) << env.err;
  EXPECT_TRUE(contains(env.out, "farfield: yes")) << env.out;
  // unseen_radiance "auto" is printed with its value: 0.8 x the mean DiffCol x DiffDir + Emit
  // over the geometry, here against the same mean taken from the frame's own pixels; by
  // default the elevations the frame does not show escape, with the interior preset not.
  EXPECT_TRUE(contains(r.out, "unseen_radiance: auto = ")) << r.out;
  // A Cycles render's emitters light others in its DiffDir: Emit is not gathered again.
  EXPECT_TRUE(contains(r.out, "emission: direct (DiffDir already holds")) << r.out;
  EXPECT_TRUE(contains(r.out, "from the header (emission auto)")) << r.out;
  EXPECT_TRUE(contains(r.out, "elevations the frame does not show escape)")) << r.out;
  const RunResult interior = hbil("info " + q(sample(1)) + " --preset " +
                                  q(std::string(HBIL_SOURCE_DIR) + "/presets/interior.json"));
  ASSERT_EQ(interior.code, 0) << interior.err;
  const size_t at = interior.out.find("unseen_radiance: auto = ");
  ASSERT_NE(at, std::string::npos) << interior.out;
  EXPECT_TRUE(contains(interior.out, "does not show as open as its top and bottom"))
      << interior.out;
  std::istringstream line(interior.out.substr(at + 24));
  float red = 0;
  line >> red;
  Params p;
  const io::InputFrame in = io::open_frame(sample(1), 1, p);
  GBuffer g = io::read_fields(in, {"depth", "diffcol", "diffdir", "emit"}, p);
  double sum = 0;
  size_t geometry = 0;
  for (size_t i = 0; i < g.pixels(); ++i)
    if (g.depth[i] < 1e9f) sum += g.diffcol[i].x * g.diffdir[i].x + g.emit[i].x, ++geometry;
  ASSERT_GT(geometry, 0u);
  const double mean = sum / double(geometry);
  EXPECT_NEAR(red, 0.8 * mean, 1e-3 * mean) << interior.out;
  // The escape pass is off by default; the sample's AO pass (1 m) is pointed out as one.
  EXPECT_TRUE(contains(interior.out,
                       "escape: off (passes.escape is \"\"); the frame has an AO "
                       "pass"))
      << interior.out;

  // Without Normal (and without a sidecar): the outputs cannot be computed and info says
  // why, exit 0 all the same; the camera is solved from Position.
  test::copy_exr(sample(1), in_frame(1), {"ViewLayer.Normal."});
  const RunResult n = hbil("info " + q(in_frame(1)));
  ASSERT_EQ(n.code, 0) << n.err;
  EXPECT_TRUE(contains(n.out, "ao: no")) << n.out;
  EXPECT_TRUE(contains(n.out, "normal: absent (looked for ViewLayer.Normal.X")) << n.out;
  EXPECT_TRUE(contains(n.out, "bentcone: no: frame 1")) << n.out;
  EXPECT_FALSE(contains(n.out, "yes, from")) << "no output is listed as computable:\n" << n.out;
  EXPECT_TRUE(contains(n.out, "camera: solved from Position")) << n.out;

  const RunResult missing = hbil("info " + q(path("in/none.exr")));
  EXPECT_EQ(missing.code, int(Exit::input)) << missing.err;
  EXPECT_TRUE(contains(missing.err, path("in/none.exr"))) << missing.err;
}

// info reads the pixels run would read: a frame whose header opens but whose pixels do not
// fails info with the exit code and the file run gives.
TEST_F(Cli, InfoFailsOnUnreadablePixelsAsRunDoes) {
  const RunResult ok = hbil("info " + q(sample(1)));
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(contains(ok.out, "pixels: read and checked: depth, normal")) << ok.out;
  test::truncate_copy(sample(1), in_frame(1), fs::file_size(sample(1)) / 2);
  fs::copy_file(sample(1, ".camera.json"), in_frame(1, ".camera.json"));
  const RunResult info = hbil("info " + q(in_frame(1)));
  const RunResult run = expect_failure(run_args(in_frame(1), path("out/out_0001.exr")), Exit::input,
                                       {in_frame(1), "cannot read"});
  EXPECT_EQ(info.code, int(Exit::input)) << info.err;
  EXPECT_EQ(info.code, run.code);
  EXPECT_TRUE(contains(info.err, "hbil: error: frame 1 (" + in_frame(1) + "): cannot read"))
      << info.err;
  // A non-finite depth: exit 5 from both.
  test::copy_exr(sample(1), in_frame(1), {}, [](Pixels& p) {
    p.at(7, 9, p.channel("ViewLayer.Depth.Z")) = std::numeric_limits<float>::infinity();
  });
  const RunResult nan = hbil("info " + q(in_frame(1)));
  EXPECT_EQ(nan.code, int(Exit::bad_data)) << nan.err;
  EXPECT_TRUE(contains(nan.err, "ViewLayer.Depth.Z")) << nan.err;
  EXPECT_TRUE(contains(nan.err, "(7, 9)")) << nan.err;
}

TEST_F(Cli, CompareAgainstItselfAndAgainstCycles) {
  const std::string out = path("out/out_0001.exr");
  ASSERT_EQ(hbil(run_args(sample(1), out, "-q")).code, 0);

  const RunResult self = hbil("compare " + q(out) + " " + q(out) + " --layer ao");
  ASSERT_EQ(self.code, 0) << self.err;
  EXPECT_TRUE(contains(self.out, "overall")) << self.out;
  EXPECT_TRUE(contains(self.out, "0.00000")) << self.out;
  EXPECT_TRUE(contains(self.out, "inf")) << self.out;

  const RunResult js = hbil("compare " + q(out) + " " + q(out) + " --layer bentcone --json");
  ASSERT_EQ(js.code, 0) << js.err;
  json j;
  ASSERT_NO_THROW(j = json::parse(js.out)) << js.out;
  EXPECT_EQ(j["overall"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(j["overall"]["psnr"], "inf");
  EXPECT_EQ(j["overall"]["pixels"].get<size_t>(), size_t(4) * kSampleW * kSampleH);
  EXPECT_EQ(j["channels"].size(), 4u);

  const RunResult cy =
      hbil("compare " + q(out) + " " + q(sample(1)) + " --layer ao --ref-layer AO --json");
  ASSERT_EQ(cy.code, 0) << cy.err;
  j = json::parse(cy.out);
  ASSERT_TRUE(j["overall"]["psnr"].is_number()) << j.dump();
  const double psnr = j["overall"]["psnr"].get<double>();
  EXPECT_GT(psnr, 10.0);
  EXPECT_LT(psnr, 40.0);
  EXPECT_GT(j["overall"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(j["mask"], "ViewLayer.Depth.Z < background");
  ASSERT_EQ(j["channels"].size(), 3u);
  EXPECT_EQ(j["channels"][0]["reference"], "ViewLayer.AO.R");

  const RunResult missing = hbil("compare " + q(out) + " " + q(sample(1)) + " --layer gi");
  EXPECT_EQ(missing.code, int(Exit::missing_pass)) << missing.err;
  EXPECT_TRUE(contains(missing.err, "no layer 'gi'")) << missing.err;
}

TEST_F(Cli, PresetDumpAppliesSet) {
  const RunResult r = hbil("preset --dump --set radius=2");
  ASSERT_EQ(r.code, 0) << r.err;
  json j;
  ASSERT_NO_THROW(j = json::parse(r.out)) << r.out;
  EXPECT_EQ(j["radius"].get<double>(), 2.0);
  Params expected;
  expected.radius = 2;
  EXPECT_EQ(j, to_json(expected));

  // --set wins over the shorthand; a preset file sits under both.
  test::write_text(path("p.json"), R"({"slices": 4, "radius": 7})");
  const RunResult s =
      hbil("preset --dump --preset " + q(path("p.json")) + " --radius 3 --set radius=0.25");
  ASSERT_EQ(s.code, 0) << s.err;
  j = json::parse(s.out);
  EXPECT_EQ(j["radius"].get<double>(), 0.25);
  EXPECT_EQ(j["slices"].get<int>(), 4);

  EXPECT_EQ(hbil("preset").code, int(Exit::usage));
  EXPECT_EQ(hbil("preset --dump --set radius=0").code, int(Exit::preset));
}

// preset --describe lists every key with its default, as the dump has it.
TEST_F(Cli, PresetDescribeListsEveryKey) {
  const RunResult r = hbil("preset --describe");
  ASSERT_EQ(r.code, 0) << r.err;
  const json d = to_json(Params{});
  for (auto it = d.begin(); it != d.end(); ++it)
    EXPECT_TRUE(contains(r.out, "\n" + it.key() + " = " + it.value().dump()) ||
                r.out.rfind(it.key() + " = " + it.value().dump(), 0) == 0)
        << it.key();
}

// The man page documents every option of every command: each "--name" that a command's
// --help lists appears in man/hbil.1 (as \-\-name).
TEST_F(Cli, ManPageDocumentsEveryOption) {
  const std::string man = test::read_text(fs::path(HBIL_SOURCE_DIR) / "man/hbil.1");
  const std::regex option("--([a-z][a-z0-9-]*)");
  for (const char* command : {"run", "info", "compare", "preset", "import-povray", "bench", "tune",
                              "farm plan", "farm run", "farm check", "farm slurm"}) {
    const RunResult r = hbil(std::string(command) + " --help");
    ASSERT_EQ(r.code, 0) << command;
    int found = 0;
    for (std::sregex_iterator it(r.out.begin(), r.out.end(), option), end; it != end; ++it) {
      const std::string name = (*it)[1].str();
      if (name == "help") continue;
      std::string escaped = "\\-\\-";
      for (char c : name) escaped += c == '-' ? std::string("\\-") : std::string(1, c);
      EXPECT_TRUE(test::contains(man, escaped)) << command << " --" << name;
      ++found;
    }
    EXPECT_GT(found, 0) << command;
  }
}

// The sample's frame 1 sidecar for an image of its own that shows the sample's w x h pixels
// from (x0, y0): the same focal length in pixels (lens scaled by 256 / w) and the principal
// point moved with the crop (Blender's shifts, in units of the image width).
void write_crop_sidecar(const std::string& path, int frame, int x0, int y0, int w, int h) {
  json j = json::parse(test::read_text(sample(frame, ".camera.json")));
  const Camera c = io::camera_from_sidecar(sample(frame, ".camera.json"));
  j["resolution"] = {w, h};
  j["lens_mm"] = j["lens_mm"].get<double>() * kSampleW / w;
  j["shift_x"] = (0.5 * w - (c.cx - x0)) / w;
  j["shift_y"] = ((c.cy - y0) - 0.5 * h) / w;
  test::write_text(path, j.dump(2));
}

// Largest difference over every channel of two EXRs of the same size.
double max_difference(const test::Pixels& a, const test::Pixels& b) {
  EXPECT_EQ(a.spec.channelnames, b.spec.channelnames);
  EXPECT_EQ(a.data.size(), b.data.size());
  double worst = 0;
  for (size_t i = 0; i < std::min(a.data.size(), b.data.size()); ++i)
    worst = std::max(worst, double(std::fabs(a.data[i] - b.data[i])));
  return worst;
}

// A crop written as compositors write it (data window 200x100 at (20, 10) of the 256x144
// display window) with the full frame's sidecar beside it: the outputs keep both windows,
// the camera is the sidecar's moved by the crop, so that they equal those of the same pixels
// given as an image of their own with a camera made for them; the display image frames the
// display window, transparent where the crop has no pixels.
TEST_F(Cli, ACropKeepsItsWindowsAndTheSidecarsCamera) {
  constexpr int kX = 20, kY = 10, kW = 200, kH = 100;
  fs::create_directories(path("alone"));
  for (int n = 1; n <= 2; ++n) {
    test::window_exr(sample(n), in_frame(n), kX, kY, kW, kH, true);
    fs::copy_file(sample(n, ".camera.json"), in_frame(n, ".camera.json"));
    const std::string alone = path("alone") + sample(n, "").substr(test::kRoomPoles.size());
    test::window_exr(sample(n), alone + ".exr", kX, kY, kW, kH, false);
    write_crop_sidecar(alone + ".camera.json", n, kX, kY, kW, kH);
  }
  RunResult r = hbil(run_args(path("in/frame_####.exr"), path("out/crop_####.exr")));
  ASSERT_EQ(r.code, 0) << r.err;
  r = hbil(run_args(path("alone/frame_####.exr"), path("out/alone_####.exr")));
  ASSERT_EQ(r.code, 0) << r.err;
  for (int n = 1; n <= 2; ++n) {
    const std::string f = "out/crop_000" + std::to_string(n);
    const test::Pixels crop = test::read_pixels(path(f + ".exr"));
    const test::Pixels alone =
        test::read_pixels(path("out/alone_000" + std::to_string(n) + ".exr"));
    EXPECT_EQ(crop.spec.x, kX);
    EXPECT_EQ(crop.spec.y, kY);
    EXPECT_EQ(crop.spec.width, kW);
    EXPECT_EQ(crop.spec.height, kH);
    EXPECT_EQ(crop.spec.full_x, 0);
    EXPECT_EQ(crop.spec.full_y, 0);
    EXPECT_EQ(crop.spec.full_width, kSampleW);
    EXPECT_EQ(crop.spec.full_height, kSampleH);
    // The cameras agree to rounding (the alone one's focal length is 25.6 / 36 x 200 px).
    const double worst = max_difference(crop, alone);
    RecordProperty("max_difference_frame_" + std::to_string(n), std::to_string(worst));
    EXPECT_LT(worst, 1e-4) << "frame " << n;
    const json cam = json::parse(crop.spec.get_string_attribute("hbil:camera"));
    const Camera full = io::camera_from_sidecar(sample(n, ".camera.json"));
    EXPECT_NEAR(cam["cx"].get<double>(), full.cx - kX, 1e-9);
    EXPECT_NEAR(cam["cy"].get<double>(), full.cy - kY, 1e-9);
    const test::Pixels png = test::read_pixels(path(f + ".png"));
    ASSERT_EQ(png.spec.width, kSampleW);
    ASSERT_EQ(png.spec.height, kSampleH);
    ASSERT_EQ(png.spec.nchannels, 4);
    EXPECT_EQ(png.at(kX - 1, kY + 5, 3), 0.f) << "left of the crop";
    EXPECT_EQ(png.at(kX + 5, kY + kH, 3), 0.f) << "below the crop";
    EXPECT_GT(png.at(kX + kW / 2, kY + kH / 2, 3), 0.f) << "inside the crop";
  }
}

// An overscan (a display window inside the data window, here 224x126 at (16, 9) of the
// sample's 256x144 pixels) with a sidecar for the display window: the guard band is searched
// like any pixel, so the outputs are those of the same pixels with the full frame's camera,
// with both windows kept; the display image is the display window's part.
TEST_F(Cli, AnOverscanSearchesItsGuardBandAndFramesTheDisplayWindow) {
  constexpr int kX = 16, kY = 9, kW = 224, kH = 126;
  for (int n = 1; n <= 2; ++n) {
    test::patch_display_window(sample(n), in_frame(n), kX, kY, kW, kH);
    // The display window's camera: the full frame's cropped (its centre moves by (kX, kY)).
    write_crop_sidecar(in_frame(n, ".camera.json"), n, kX, kY, kW, kH);
  }
  RunResult r = hbil(run_args(path("in/frame_####.exr"), path("out/over_####.exr")));
  ASSERT_EQ(r.code, 0) << r.err;
  r = hbil(
      run_args(test::kRoomPoles + "/frame_####.exr", path("out/plain_####.exr"), "--frames 1-2"));
  ASSERT_EQ(r.code, 0) << r.err;
  for (int n = 1; n <= 2; ++n) {
    const std::string id = "000" + std::to_string(n);
    const test::Pixels over = test::read_pixels(path("out/over_" + id + ".exr"));
    const test::Pixels plain = test::read_pixels(path("out/plain_" + id + ".exr"));
    EXPECT_EQ(over.spec.x, 0);
    EXPECT_EQ(over.spec.width, kSampleW);
    EXPECT_EQ(over.spec.full_x, kX);
    EXPECT_EQ(over.spec.full_y, kY);
    EXPECT_EQ(over.spec.full_width, kW);
    EXPECT_EQ(over.spec.full_height, kH);
    const double worst = max_difference(over, plain);
    RecordProperty("max_difference_frame_" + std::to_string(n), std::to_string(worst));
    EXPECT_LT(worst, 1e-4) << "frame " << n;
    const test::Pixels png = test::read_pixels(path("out/over_" + id + ".png"));
    const test::Pixels plain_png = test::read_pixels(path("out/plain_" + id + ".png"));
    ASSERT_EQ(png.spec.width, kW);
    ASSERT_EQ(png.spec.height, kH);
    double png_worst = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        for (int c = 0; c < 4; ++c)
          png_worst = std::max(
              png_worst, double(std::fabs(png.at(x, y, c) - plain_png.at(x + kX, y + kY, c))));
    EXPECT_LE(png_worst, 1.5 / 255) << "frame " << n;
  }
}

// compare takes each image's pixels where its data window puts them: a crop is compared
// with the part of the full frame it shows (an overscan's output with a render of the frame
// alone), and a reference that does not lie within the test is exit 5, naming both windows.
TEST_F(Cli, CompareMatchesPixelsByTheirDataWindows) {
  test::window_exr(sample(1), in_frame(1), 20, 10, 200, 100, true);
  RunResult r = hbil("compare " + q(sample(1)) + " " + q(in_frame(1)) +
                     " --layer DiffCol --mask none --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["overall"]["pixels"].get<size_t>(), size_t(3) * 200 * 100);
  EXPECT_EQ(j["overall"]["rmse"].get<double>(), 0.0);
  // Shifted by one pixel, the same crop no longer matches the frame.
  test::window_exr(sample(1), in_frame(2), 21, 10, 200, 100, false);
  r = hbil("compare " + q(in_frame(2)) + " " + q(in_frame(1)) + " --layer DiffCol --json");
  ASSERT_EQ(r.code, 0) << r.err;  // same size: pixel for pixel
  EXPECT_GT(json::parse(r.out)["overall"]["rmse"].get<double>(), 0.0);
  r = hbil("compare " + q(in_frame(1)) + " " + q(sample(1)) + " --layer DiffCol");
  EXPECT_EQ(r.code, int(Exit::bad_data)) << r.err;
  EXPECT_TRUE(contains(r.err, "is 200x100 at (20, 10) but")) << r.err;
  EXPECT_TRUE(contains(r.err, "is 256x144, which does not lie within it")) << r.err;
}

// A data window that moves inside a sequence (same size, another origin): exit 5 from the
// headers, before any frame is computed, as for a resolution change.
TEST_F(Cli, ADataWindowThatMovesInASequenceIsBadData) {
  test::window_exr(sample(1), in_frame(1), 20, 10, 200, 100, true);
  test::window_exr(sample(2), in_frame(2), 24, 10, 200, 100, true);
  for (int n = 1; n <= 2; ++n)
    fs::copy_file(sample(n, ".camera.json"), in_frame(n, ".camera.json"));
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::bad_data,
                 {"frame 2", "data window at (24, 10) differs from (20, 10)"});
  const RunResult r = hbil("info " + q(in_frame(2)));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "windows: data 200x100 at (24, 10), display 256x144 at (0, 0)"))
      << r.out;
}

// A sidecar that is neither for the display window nor the image: exit 6, both sizes named.
TEST_F(Cli, ASidecarForAnotherDisplayWindowIsRefused) {
  test::window_exr(sample(1), in_frame(1), 20, 10, 200, 100, true);
  test::write_sidecar(in_frame(1, ".camera.json"), 200, 100);
  expect_failure(run_args(path("in/frame_####.exr"), path("out/out_####.exr")), Exit::camera,
                 {"frame 1", "camera sidecar frame_0001.camera.json is for 200x100",
                  "display window is 256x144", "data window 200x100 at (20, 10)"});
}

}  // namespace
}  // namespace hbil
