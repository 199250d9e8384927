// accuracy_test.cpp: AO against the Cycles AO pass of the Blender samples (samples/README.md:
// 512 spp, World > Ambient Occlusion > Distance 1.0 = the default radius). Same measure as
// `hbil compare --layer ao --ref-layer AO`: PSNR (peak 1) over pixels with depth < 1e9, all 8
// frames. Bounds sit just below what the default preset (bitmask) measures (README
// "Accuracy"); a change that loses more than ~0.3 dB fails here. The horizon method must stay
// below the bitmask on both scenes: that is why the bitmask is the default.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <tuple>

#include "hbil/ao_frame.h"
#include "hbil/error_stats.h"
#include "io/exr_frame.h"
#include "io/sequence.h"
#include "pipeline/bench.h"
#include "test_util.h"

namespace hbil {
namespace {

// The helpers add to `all` and stop at the first fatal failure (a missing reference channel
// must fail the test, not be indexed); their callers below return what was gathered, with the
// test already failed.
void add_ao_error(const std::string& scene, const Params& p, ErrorStats& all) {
  const io::FramePattern pattern(std::string(HBIL_SOURCE_DIR) + "/samples/" + scene +
                                 "/frame_####.exr");
  for (int frame = 1; frame <= 8; ++frame) {
    const io::InputFrame in = io::open_frame(pattern.path(frame), frame, p);
    GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
    const AoFrame f = compute_ao_frame(g, io::find_camera(in, g, p), p);
    auto img = OIIO::ImageInput::open(in.path);
    ASSERT_TRUE(img) << in.path;
    const int c = in.spec.channelindex("ViewLayer.AO.R");
    ASSERT_GE(c, 0) << in.path << " has no ViewLayer.AO.R";
    std::vector<float> ref(g.pixels());
    ASSERT_TRUE(img->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, ref.data()))
        << img->geterror();
    for (size_t i = 0; i < g.pixels(); ++i)
      if (g.depth[i] < 1e9f) all.add(f.ao[i], ref[i]);
  }
}

ErrorStats ao_error(const std::string& scene, const Params& p) {
  ErrorStats all;
  add_ao_error(scene, p, all);
  return all;
}

TEST(AccuracyAgainstCycles, CourtyardAo) {
  const ErrorStats e = ao_error("courtyard", Params{});
  EXPECT_GT(e.count, 200000u);
  EXPECT_GT(e.psnr(), 23.2) << "rmse " << e.rmse() << " mean "
                            << e.mean_error();  // measured 23.46 dB
}

// The thin-object scene: poles and a fence. The default bitmask (each sample as thick as the
// back-face layer says) lets light pass behind them; the horizon method (infinitely thick
// occluders) measures 18.56 dB here.
TEST(AccuracyAgainstCycles, RoomWithPolesAo) {
  const ErrorStats e = ao_error("room_poles", Params{});
  EXPECT_GT(e.count, 200000u);
  EXPECT_GT(e.psnr(), 18.6) << "rmse " << e.rmse() << " mean "
                            << e.mean_error();  // measured 18.85 dB
}

TEST(AccuracyAgainstCycles, BitmaskBeatsHorizonOnBothScenes) {
  Params horizon;
  horizon.method = "horizon";
  horizon.steps = 6;  // the horizon method's own best steps (README sweep)
  for (const char* scene : {"courtyard", "room_poles"})
    EXPECT_GT(ao_error(scene, Params{}).psnr(), ao_error(scene, horizon).psnr()) << scene;
}

// `indirect` (1 bounce) against Cycles' DiffCol × DiffInd rendered with 1 diffuse bounce
// (samples/<scene>/bounce1), as `hbil compare --layer indirect --ref-layer 'DiffCol*DiffInd'`:
// all three channels of the non-background pixels of the 8 frames.
void add_indirect_error(const std::string& scene, const Params& p, ErrorStats& all) {
  const std::string dir = std::string(HBIL_SOURCE_DIR) + "/samples/" + scene;
  const io::FramePattern pattern(dir + "/frame_####.exr"), ref(dir + "/bounce1/frame_####.exr");
  for (int frame = 1; frame <= 8; ++frame) {
    const io::InputFrame in = io::open_frame(pattern.path(frame), frame, p);
    GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
    const AoFrame f = compute_ao_frame(g, io::find_camera(in, g, p), p);
    auto img = OIIO::ImageInput::open(ref.path(frame));
    ASSERT_TRUE(img) << ref.path(frame);
    auto layer = [&](const char* pass, std::vector<float>& v) {
      const int c = img->spec().channelindex(std::string("ViewLayer.") + pass + ".R");
      ASSERT_GE(c, 0) << ref.path(frame) << " has no ViewLayer." << pass << ".R";
      v.resize(g.pixels() * 3);
      ASSERT_TRUE(img->read_image(0, 0, c, c + 3, OIIO::TypeDesc::FLOAT, v.data()))
          << img->geterror();
    };
    std::vector<float> col, ind;
    ASSERT_NO_FATAL_FAILURE(layer("DiffCol", col));
    ASSERT_NO_FATAL_FAILURE(layer("DiffInd", ind));
    for (size_t i = 0; i < g.pixels(); ++i)
      if (g.depth[i] < 1e9f) {
        const Vec3 v = f.indirect[i];
        for (int k = 0; k < 3; ++k) all.add((&v.x)[k], col[3 * i + k] * ind[3 * i + k]);
      }
  }
}

ErrorStats indirect_error(const std::string& scene, const Params& p) {
  ErrorStats all;
  add_indirect_error(scene, p, all);
  return all;
}

Params indirect_params() {
  Params p;
  p.outputs = {"indirect"};
  return p;
}

// The screen-space gather alone (unseen_radiance 0): what the thickness models decide.
Params gather_only_params() {
  Params p = indirect_params();
  p.unseen_radiance_auto = false;
  return p;
}

TEST(AccuracyAgainstCycles, CourtyardIndirectOneBounce) {
  const ErrorStats e = indirect_error("courtyard", indirect_params());
  EXPECT_GT(e.count, 600000u);
  std::cout << "courtyard: indirect " << e.psnr() << " dB\n";
  EXPECT_GT(e.psnr(), 34.75) << "rmse " << e.rmse() << " mean "
                             << e.mean_error();  // measured 35.09 dB (33.31 with the fill at 0.8)
  const double gather = indirect_error("courtyard", gather_only_params()).psnr();
  std::cout << "courtyard: indirect, gather only " << gather << " dB\n";
  EXPECT_GT(gather, 28.2);  // measured 28.48
}

TEST(AccuracyAgainstCycles, RoomWithPolesIndirectOneBounce) {
  const ErrorStats e = indirect_error("room_poles", indirect_params());
  EXPECT_GT(e.count, 600000u);
  std::cout << "room_poles: indirect " << e.psnr() << " dB\n";
  // The glowing cube's light is in its neighbours' DiffDir: gathering its Emit as well
  // (emission "gathered") gives 30.67 dB here and 28.92 for the gather alone. The default
  // fill's level (1.2 x the frame's mean direct radiance) stands for the unseen surfaces'
  // bounced light as well, which this one-bounce render does not have: room_poles' indirect
  // comes out brighter than it (33.36 dB with the level at 0.8).
  EXPECT_GT(e.psnr(), 28.45) << "rmse " << e.rmse() << " mean "
                             << e.mean_error();  // measured 28.75 dB
  const double gather = indirect_error("room_poles", gather_only_params()).psnr();
  std::cout << "room_poles: indirect, gather only " << gather << " dB\n";
  EXPECT_GT(gather, 29.1);  // measured 29.41
}

// The samples carry a BackFaces.Depth.Z layer (samples/blender/backfaces.py). Measured
// thickness beats the constant 0.4 on the gather's indirect light in both scenes (courtyard
// 28.52 vs 27.85 dB, room_poles 28.92 vs 28.50) and on the thin-object scene's AO (18.85 vs
// 18.68); the courtyard's AO loses 0.1 dB (23.46 vs 23.56), so it is not asserted. With
// unseen_radiance "auto" the fill of what the gather leaves empty outweighs it (courtyard
// 33.36 vs 33.41 dB, room_poles 30.67 vs 31.04): the gather alone is compared.
TEST(AccuracyAgainstCycles, BackFaceThicknessBeatsTheConstant) {
  const Params constant =
      apply_set(apply_set(gather_only_params(), "passes.backdepth=\"\""), "thickness_extent=false");
  for (const char* scene : {"courtyard", "room_poles"})
    EXPECT_GT(indirect_error(scene, gather_only_params()).psnr(),
              indirect_error(scene, constant).psnr() + 0.3)
        << scene;
  const Params ao,
      ao_constant = apply_set(apply_set(ao, "passes.backdepth=\"\""), "thickness_extent=false");
  EXPECT_GT(ao_error("room_poles", ao).psnr(), ao_error("room_poles", ao_constant).psnr() + 0.1);
}

// Without a back-face layer, the thickness from each object's extent on screen (up to the
// constant 0.4; thickness_extent) against the constant alone, on the samples' indirect light
// (measured: room_poles 28.73 against 28.50 dB, courtyard 28.15 against 27.85 dB; the gather
// alone, as above) and on room_poles' AO.
TEST(AccuracyAgainstCycles, ExtentThicknessBeatsTheConstantWithoutBackFaces) {
  const Params extent = apply_set(gather_only_params(), "passes.backdepth=\"\"");
  const Params constant = apply_set(extent, "thickness_extent=false");
  for (const char* scene : {"room_poles", "courtyard"}) {
    const double e = indirect_error(scene, extent).psnr(),
                 c = indirect_error(scene, constant).psnr();
    std::cout << scene << ": indirect " << e << " dB from the extent, " << c << " dB constant\n";
    EXPECT_GT(e, c + 0.15) << scene;
  }
  const Params ao = apply_set(Params{}, "passes.backdepth=\"\"");
  const double e = ao_error("room_poles", ao).psnr(),
               c = ao_error("room_poles", apply_set(ao, "thickness_extent=false")).psnr();
  std::cout << "room_poles: ao " << e << " dB from the extent, " << c << " dB constant\n";
  EXPECT_GT(e, c + 0.1);
}

// unseen_radiance "auto" over the temporal chain, composite against the 8-bounce Combined of
// all 8 frames (as `hbil bench --ref composite=...:Combined`; README "Light from what the
// frame does not show": the default, where the elevations the frame does not show escape,
// room_poles 30.28 dB, courtyard 30.73 dB, 27.56 and 28.97 with that fill's level at 0.8
// instead of 1.2 and 2 slices instead of "auto"'s 1 (2 on the chain's first frame); with
// unseen_carry (presets/interior.json) 31.80 and 31.81; with unseen_radiance 0, 22.36 and
// 25.64). Bounds about 0.2 dB below. On the open
// courtyard the frame's sky must dim the fill: with the frame's mean radiance in every empty
// direction it measured 25.05 dB.
TEST(AccuracyAgainstCycles, UnseenRadianceAutoOnBothSamples) {
  Params off, interior;
  off.unseen_radiance_auto = false;
  interior.unseen_carry = true;
  interior.unseen_carry_auto = false;
  for (const auto& [scene, bound, carried] :
       {std::tuple{"room_poles", 30.05, 31.55}, {"courtyard", 30.55, 31.6}}) {
    const std::string in = std::string(HBIL_SOURCE_DIR) + "/samples/" + scene + "/frame_####.exr";
    pipeline::BenchSettings s;
    s.shot = in;
    s.configs = {{"off", off}, {"default", Params{}}, {"interior", interior}};
    s.refs = {pipeline::parse_bench_reference("composite=" + in + ":Combined")};
    const pipeline::BenchResult r = pipeline::run_bench(s);
    const double base = r.configs[0].errors.at("composite").psnr();
    const double with = r.configs[1].errors.at("composite").psnr();
    const double with_carry = r.configs[2].errors.at("composite").psnr();
    std::cout << scene << ": composite " << base << " dB off, " << with << " dB default, "
              << with_carry << " dB carried\n";
    EXPECT_GT(with, bound) << scene;
    EXPECT_GT(with, base + 3.0) << scene;
    EXPECT_GT(with_carry, carried) << scene;
    EXPECT_GT(with_carry, base + 5.0) << scene;
  }
}

// The escape pass (passes.escape): each sample's committed 1-spp AO pass rendered with a
// distance of 1000 m (samples/<scene>/escape/, samples/README.md), appended to its frames as
// ViewLayer.Escape.R; composite over the temporal chain against the 8-bounce render, as
// UnseenRadianceAutoOnBothSamples. Measured 2026-12-05: room_poles 30.28 -> 30.66 dB,
// courtyard 30.73 -> 31.55 dB.
TEST(AccuracyAgainstCycles, EscapePassOnBothSamples) {
  for (const auto& [scene, bound, gain] :
       {std::tuple{"room_poles", 30.5, 0.25}, {"courtyard", 31.3, 0.6}}) {
    const test::TempDir dir(std::string("escape-") + scene);
    const std::string src = std::string(HBIL_SOURCE_DIR) + "/samples/" + scene;
    char name[32];
    for (int frame = 1; frame <= 8; ++frame) {
      std::snprintf(name, sizeof name, "frame_%04d", frame);
      const std::string base = src + "/" + name;
      OIIO::ImageBuf g(base + ".exr"), e(src + "/escape/" + name + ".exr");
      ASSERT_TRUE(g.read(0, 0, true) && e.read(0, 0, true)) << base;
      ASSERT_GE(e.spec().channelindex("ViewLayer.AO.R"), 0) << name;
      OIIO::ImageBuf escape = OIIO::ImageBufAlgo::channels(
          e, 1, {e.spec().channelindex("ViewLayer.AO.R")}, {}, {"ViewLayer.Escape.R"});
      OIIO::ImageBuf both = OIIO::ImageBufAlgo::channel_append(g, escape);
      ASSERT_TRUE(both.write(dir / (std::string(name) + ".exr"))) << both.geterror();
      std::filesystem::copy_file(base + ".camera.json", dir / (std::string(name) + ".camera.json"));
    }
    const std::string in = dir / "frame_####.exr";
    Params with;
    with.passes["escape"] = "Escape";
    pipeline::BenchSettings s;
    s.shot = in;
    s.configs = {{"default", Params{}}, {"escape", with}};
    s.refs = {pipeline::parse_bench_reference("composite=" + in + ":Combined")};
    const pipeline::BenchResult r = pipeline::run_bench(s);
    const double base = r.configs[0].errors.at("composite").psnr();
    const double esc = r.configs[1].errors.at("composite").psnr();
    std::cout << scene << ": composite " << base << " dB default, " << esc << " dB escape\n";
    EXPECT_GT(esc, bound) << scene;
    EXPECT_GT(esc, base + gain) << scene;
  }
}

}  // namespace
}  // namespace hbil
