// scene_scale_test.cpp: gather_radius, thickness and gather_thickness "auto" (scene_scale.h):
// the depth percentiles of a frame with known depths, the values derived from them, the
// presets' "auto" and its errors.

#include "hbil/scene_scale.h"

#include <gtest/gtest.h>

#include "hbil/error.h"
#include "test_util.h"

namespace hbil {
namespace {

// A 10 x 10 frame whose pixel i has depth 1 + i/10 (1.0 .. 10.9), the last row background.
GBuffer ramp(double background) {
  GBuffer g;
  g.width = g.height = 10;
  for (int i = 0; i < 100; ++i)
    g.depth.push_back(i < 90 ? 1.f + float(i) / 10.f : float(background));
  return g;
}

TEST(SceneScale, PercentilesOfTheGeometryPixels) {
  Params p;
  Camera cam;
  cam.fx = 5;  // 10 px wide: the frame's width at depth z is 2 z
  const SceneScale s = measure_scene(ramp(2e9), cam, p);
  EXPECT_EQ(s.geometry, 90u);
  // 90 depths 1.0 .. 9.9: the k-th smallest at k = round(q * 89).
  EXPECT_FLOAT_EQ(float(s.depth_median), 1.f + 45 / 10.f);  // 5.5
  EXPECT_FLOAT_EQ(float(s.depth_p10), 1.f + 9 / 10.f);
  EXPECT_FLOAT_EQ(float(s.depth_p90), 1.f + 80 / 10.f);
  EXPECT_NEAR(s.width_at_median, 2 * 5.5, 1e-5);
}

TEST(SceneScale, AutoValuesFollowTheMedianDepth) {
  Params p;
  Camera cam;
  cam.fx = 5;
  std::string why;
  const Params r = resolve_scene_params(p, measure_scene(ramp(2e9), cam, p), &why);
  EXPECT_FALSE(r.gather_radius_auto || r.thickness_auto || r.gather_thickness_auto);
  EXPECT_NEAR(r.gather_radius, 11.0, 1e-5);
  EXPECT_NEAR(r.thickness, 0.4 * p.radius, 1e-9);  // 0.15 x 5.5 = 0.825, capped at 0.4 x 1
  EXPECT_NEAR(r.gather_thickness, 0.3 * 5.5, 1e-6);
  EXPECT_TRUE(test::contains(why, "gather_radius 11")) << why;
  EXPECT_TRUE(test::contains(why, "median depth 5.5")) << why;
  // A scene 10 x smaller: everything 10 x smaller, the cap no longer reached.
  GBuffer small = ramp(2e9);
  for (int i = 0; i < 90; ++i) small.depth[size_t(i)] /= 10;
  const Params q = resolve_scene_params(p, measure_scene(small, cam, p));
  EXPECT_NEAR(q.gather_radius, 1.1, 1e-6);
  EXPECT_NEAR(q.thickness, 0.15 * 0.55, 1e-6);
  EXPECT_NEAR(q.gather_thickness, 0.3 * 0.55, 1e-6);
}

TEST(SceneScale, GivenValuesAreKept) {
  Camera cam;
  cam.fx = 5;
  Params p = apply_set(apply_set(Params{}, "gather_radius=3"), "thickness=0.25");
  EXPECT_FALSE(p.gather_radius_auto);
  EXPECT_FALSE(p.thickness_auto);
  const Params r = resolve_scene_params(p, measure_scene(ramp(2e9), cam, p));
  EXPECT_EQ(r.gather_radius, 3);
  EXPECT_EQ(r.thickness, 0.25);
  EXPECT_EQ(r.gather_thickness, 0.25) << "auto gather_thickness follows a given thickness";
}

TEST(SceneScale, NoGeometryKeepsTheNumbers) {
  Camera cam;
  cam.fx = 5;
  GBuffer g = ramp(2e9);
  for (float& z : g.depth) z = 2e9f;
  const Params p;
  std::string why;
  const Params r = resolve_scene_params(p, measure_scene(g, cam, p), &why);
  EXPECT_EQ(r.gather_radius, p.gather_radius);
  EXPECT_EQ(r.thickness, p.thickness);
  EXPECT_EQ(r.gather_thickness, p.thickness);
  EXPECT_TRUE(test::contains(why, "no geometry")) << why;
}

TEST(SceneScale, AutoInPresets) {
  const Params p =
      params_from_json(nlohmann::json{{"gather_radius", 2.5}, {"thickness", "auto"}}, "preset");
  EXPECT_FALSE(p.gather_radius_auto);
  EXPECT_EQ(p.gather_radius, 2.5);
  EXPECT_TRUE(p.thickness_auto);
  EXPECT_EQ(to_json(apply_set(p, "gather_radius=auto"))["gather_radius"], "auto");
  test::expect_error([] { apply_set(Params{}, "gather_radius=big"); }, Exit::preset,
                     {"gather_radius", "a number or \"auto\""});
  test::expect_error([] { apply_set(Params{}, "thickness=true"); }, Exit::preset,
                     {"thickness", "a number or \"auto\""});
  test::expect_error([] { apply_set(Params{}, "gather_thickness=-1"); }, Exit::preset,
                     {"gather_thickness", "out of range"});
}

}  // namespace
}  // namespace hbil

namespace hbil {
namespace {

// A chunk of a shot resolves "auto" from the shot's first frame on disk, as the whole run
// does: its frames carry the same parameters, and a chunk starting at a cut is the whole
// run's frame to the bit.
TEST(SceneScale, ChunksUseTheShotsFirstFrame) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kSourceDir + "/samples/room_cut/frame_####.exr";
  auto run = [&](const std::string& frames, const std::string& out) {
    const auto r = test::run_hbil(
        "run " + test::q(in) + frames + " -o " + test::q(dir / out) + " -q --no-display",
        dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
  };
  run("", "all/f_####.exr");
  run(" --frames 4-5", "chunk/f_####.exr");
  const test::Pixels whole = test::read_pixels(dir / "all/f_0004.exr");
  const test::Pixels chunk = test::read_pixels(dir / "chunk/f_0004.exr");
  EXPECT_EQ(whole.spec.get_string_attribute("hbil:preset"),
            chunk.spec.get_string_attribute("hbil:preset"));
  EXPECT_EQ(whole.data, chunk.data) << "frame 4 is a cut: no history in either run";
}

}  // namespace
}  // namespace hbil
