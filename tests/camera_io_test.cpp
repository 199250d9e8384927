// camera_io_test.cpp: sidecar parsing, EXR camera attributes and the Position solver.
//
// Reference data: tests/data/camera/*.exr are tiny Cycles renders (Blender 3.4) with their
// sidecars written by samples/blender/export_camera.py (tests/data/camera/make.py). In
// Blender 3.4 the Position pass holds the first sample's hit point at the pixel centre
// (not a filtered average), so every foreground pixel must project onto its centre.
// Tolerances are set once, at the top of the namespace below.

#include "io/camera_io.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "hbil/error.h"

namespace hbil::io {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kSidecarReprojPx = 0.05;       // Blender pixels through the sidecar camera
constexpr double kSolvedRmsPx = 0.1;            // solved camera, Blender data
constexpr double kSolvedIntrinsicsRel = 0.005;  // solved vs sidecar fx, fy, cx, cy (0.5 %)
constexpr double kNoiseFreeRel = 1e-6;          // synthetic, noise-free solve

const std::string kDataDir = std::string(HBIL_SOURCE_DIR) + "/tests/data/camera/";

// Runs f, expects Error with the given code and a message containing every needle.
template <typename F>
void expect_error(F&& f, Exit code, std::initializer_list<std::string> needles) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const Error& e) {
    EXPECT_EQ(int(e.code()), int(code)) << e.what();
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos)
          << "message \"" << e.what() << "\" lacks \"" << n << "\"";
  }
}

Mat3d rotation_xyz(double ax, double ay, double az) {
  Mat3d x, y, z;
  x.m[1][1] = std::cos(ax), x.m[1][2] = -std::sin(ax), x.m[2][1] = std::sin(ax),
  x.m[2][2] = std::cos(ax);
  y.m[0][0] = std::cos(ay), y.m[0][2] = std::sin(ay), y.m[2][0] = -std::sin(ay),
  y.m[2][2] = std::cos(ay);
  z.m[0][0] = std::cos(az), z.m[0][1] = -std::sin(az), z.m[1][0] = std::sin(az),
  z.m[1][1] = std::cos(az);
  return z * y * x;
}

double max_abs_diff(const Mat3d& a, const Mat3d& b) {
  double d = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d = std::max(d, std::abs(a.m[i][j] - b.m[i][j]));
  return d;
}

// A test camera: 320x240, non-square focal lengths, off-centre principal point.
Camera test_camera() {
  Camera c;
  c.width = 320;
  c.height = 240;
  c.fx = 410.5;
  c.fy = 395.25;
  c.cx = 171.3;
  c.cy = 108.9;
  c.R = rotation_xyz(0.3, -0.7, 0.15);
  c.t = {0.4, -1.2, 6.5};
  return c;
}

// World positions at pixel centres, depth uniform in [2, 12]; about 20 % background.
std::vector<Vec3> positions_of(const Camera& c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> depth(2, 12), unit(0, 1);
  std::vector<Vec3> pos(size_t(c.width) * c.height);
  for (int row = 0; row < c.height; ++row)
    for (int col = 0; col < c.width; ++col) {
      if (unit(rng) < 0.2) continue;
      const Vec3d v = c.unproject(col + 0.5, row + 0.5, depth(rng));
      pos[size_t(row) * c.width + col] = Vec3(c.view_to_world(v));
    }
  return pos;
}

void expect_intrinsics_near(const Camera& got, const Camera& want, double rel) {
  EXPECT_NEAR(got.fx, want.fx, rel * want.fx);
  EXPECT_NEAR(got.fy, want.fy, rel * want.fy);
  EXPECT_NEAR(got.cx, want.cx, rel * want.width);
  EXPECT_NEAR(got.cy, want.cy, rel * want.height);
}

// --------------------------------------------------------------------------------------
// Sidecars

json sidecar_json() {
  return json::parse(R"({
    "format": "hbil-camera-1", "source": "blender", "frame": 3, "resolution": [200, 100],
    "pixel_aspect": 1.0, "type": "PERSP",
    "matrix_world": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
    "lens_mm": 50.0, "sensor_width_mm": 36.0, "sensor_height_mm": 24.0, "sensor_fit": "AUTO",
    "shift_x": 0.0, "shift_y": 0.0, "clip_start": 0.1, "clip_end": 100.0 })");
}

TEST(CameraSidecar, PathReplacesImageExtension) {
  EXPECT_EQ(sidecar_path_for("dir/frame_0001.exr"), "dir/frame_0001.camera.json");
  EXPECT_EQ(sidecar_path_for("/a/b.c/shot.EXR"), "/a/b.c/shot.camera.json");
  EXPECT_EQ(sidecar_path_for("frame.0001"), "frame.0001.camera.json");
}

TEST(CameraSidecar, IdentityCameraLooksDownMinusZ) {
  const Camera c = camera_from_sidecar_json(sidecar_json(), "x/test.camera.json");
  EXPECT_EQ(c.width, 200);
  EXPECT_EQ(c.height, 100);
  EXPECT_EQ(c.source, "sidecar test.camera.json");
  // AUTO, landscape: fx = lens / sensor_width * width.
  EXPECT_DOUBLE_EQ(c.fx, 50.0 / 36.0 * 200);
  EXPECT_DOUBLE_EQ(c.fy, c.fx);
  EXPECT_DOUBLE_EQ(c.cx, 100);
  EXPECT_DOUBLE_EQ(c.cy, 50);
  // Blender camera space (x right, y up, looking down -z) -> vision (x right, y down, +z).
  const Vec3d v = c.world_to_view({1, 0.5, -10});
  EXPECT_NEAR(v.x, 1, 1e-12);
  EXPECT_NEAR(v.y, -0.5, 1e-12);
  EXPECT_NEAR(v.z, 10, 1e-12);
}

TEST(CameraSidecar, MatrixWorldPlacesCamera) {
  json j = sidecar_json();
  // Camera at (1, 2, 3), rotated 90 degrees about world Z: local -Z still points down
  // world -Z, local +X points along world +Y.
  j["matrix_world"] = {{0, -1, 0, 1}, {1, 0, 0, 2}, {0, 0, 1, 3}, {0, 0, 0, 1}};
  const Camera c = camera_from_sidecar_json(j, "t");
  const Vec3d centre = c.centre();
  EXPECT_NEAR(centre.x, 1, 1e-12);
  EXPECT_NEAR(centre.y, 2, 1e-12);
  EXPECT_NEAR(centre.z, 3, 1e-12);
  const Vec3d v = c.world_to_view({1, 2 + 0.5, 3 - 4});  // right of the camera, 4 ahead
  EXPECT_NEAR(v.x, 0.5, 1e-12);
  EXPECT_NEAR(v.y, 0, 1e-12);
  EXPECT_NEAR(v.z, 4, 1e-12);
  // Blender ignores object scale for the projection.
  j["matrix_world"] = {{0, -2, 0, 1}, {2, 0, 0, 2}, {0, 0, 2, 3}, {0, 0, 0, 1}};
  EXPECT_LT(max_abs_diff(camera_from_sidecar_json(j, "t").R, c.R), 1e-15);
}

TEST(CameraSidecar, SensorFitShiftAndPixelAspect) {
  json j = sidecar_json();
  j["shift_x"] = 0.1;
  j["shift_y"] = 0.1;
  Camera c = camera_from_sidecar_json(j, "t");
  // Shift in units of the larger side; +shift_x moves the view right (principal point left),
  // +shift_y moves it up (principal point down, rows top-down).
  EXPECT_DOUBLE_EQ(c.cx, 100 - 0.1 * 200);
  EXPECT_DOUBLE_EQ(c.cy, 50 + 0.1 * 200);

  j["sensor_fit"] = "VERTICAL";  // fy = lens / sensor_height * height
  c = camera_from_sidecar_json(j, "t");
  EXPECT_DOUBLE_EQ(c.fy, 50.0 / 24.0 * 100);
  EXPECT_DOUBLE_EQ(c.fx, c.fy);
  EXPECT_DOUBLE_EQ(c.cx, 100 - 0.1 * 100);
  EXPECT_DOUBLE_EQ(c.cy, 50 + 0.1 * 100);

  // AUTO on a portrait image: sensor_width against the height.
  j["sensor_fit"] = "AUTO";
  j["resolution"] = {100, 200};
  c = camera_from_sidecar_json(j, "t");
  EXPECT_DOUBLE_EQ(c.fy, 50.0 / 36.0 * 200);
  EXPECT_DOUBLE_EQ(c.cy, 100 + 0.1 * 200);

  // pixel_aspect = aspect_y / aspect_x = 2 (pixels twice as tall as wide): 200 x 100 pixels
  // are square overall, AUTO still fits horizontally; fy = fx / 2.
  j["resolution"] = {200, 100};
  j["pixel_aspect"] = 2.0;
  c = camera_from_sidecar_json(j, "t");
  EXPECT_DOUBLE_EQ(c.fx, 50.0 / 36.0 * 200);
  EXPECT_DOUBLE_EQ(c.fy, c.fx / 2);
  EXPECT_DOUBLE_EQ(c.cy, 50 + 0.1 * 200 / 2);
}

TEST(CameraSidecar, OptionalKeysHaveDefaults) {
  json j = sidecar_json();
  j.erase("pixel_aspect");
  j.erase("shift_x");
  j.erase("shift_y");
  j.erase("clip_start");
  j.erase("frame");
  const Camera c = camera_from_sidecar_json(j, "t");
  EXPECT_DOUBLE_EQ(c.cx, 100);
  EXPECT_DOUBLE_EQ(c.fy, c.fx);
}

TEST(CameraSidecar, MissingKeysAreNamed) {
  for (const char* key : {"format", "type", "resolution", "matrix_world", "lens_mm",
                          "sensor_width_mm", "sensor_height_mm", "sensor_fit"}) {
    json j = sidecar_json();
    j.erase(key);
    expect_error([&] { camera_from_sidecar_json(j, "cam.json"); }, Exit::camera,
                 {"cam.json", std::string("\"") + key + "\"", "missing"});
  }
}

TEST(CameraSidecar, WrongTypesAndValuesAreNamed) {
  const std::vector<std::pair<std::string, json>> bad = {
      {"lens_mm", "50"},
      {"lens_mm", -1},
      {"shift_x", "0"},
      {"pixel_aspect", 0},
      {"sensor_fit", "DIAGONAL"},
      {"resolution", {256}},
      {"resolution", {256.5, 144}},
      {"matrix_world", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
      {"matrix_world", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 1, 1}}},
      {"matrix_world", {{1, 1, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}},
      {"matrix_world", {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}},
      {"format", "hbil-camera-2"},
      {"type", 1},
  };
  for (const auto& [key, value] : bad) {
    json j = sidecar_json();
    j[key] = value;
    SCOPED_TRACE(key + " = " + value.dump());
    expect_error([&] { camera_from_sidecar_json(j, "cam.json"); }, Exit::camera,
                 {"cam.json", "\"" + key + "\""});
  }
}

// Keys each valid whose combination is not a camera (found by tests/fuzz/fuzz_sidecar: a
// sensor height of 2e-319 mm made the focal length infinite).
TEST(CameraSidecar, ValidKeysThatGiveNoFiniteFocalLengthAreRefused) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"sensor_width_mm", 2e-319}, {"lens_mm", 1e308}, {"shift_x", 1e308}}) {
    json j = sidecar_json();
    j[key] = value;
    SCOPED_TRACE(key);
    expect_error([&] { camera_from_sidecar_json(j, "cam.json"); }, Exit::camera,
                 {"cam.json", "focal length of", "not a camera"});
  }
}

TEST(CameraSidecar, UnsupportedTypesAreRefused) {
  for (const char* type : {"ORTHO", "PANO"}) {
    json j = sidecar_json();
    j["type"] = type;
    expect_error([&] { camera_from_sidecar_json(j, "cam.json"); }, Exit::camera,
                 {"\"type\"", type, "PERSP"});
  }
  expect_error([&] { camera_from_sidecar_json(json::array(), "cam.json"); }, Exit::camera,
               {"cam.json", "object"});
}

TEST(CameraSidecar, FileErrors) {
  const fs::path dir =
      fs::temp_directory_path() / ("hbil_camera_io_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string bad = (dir / "bad.camera.json").string();
  std::ofstream(bad) << "{ \"format\": \"hbil-camera-1\", ";
  expect_error([&] { camera_from_sidecar(bad); }, Exit::camera, {bad, "JSON"});
  const std::string good = (dir / "good.camera.json").string();
  std::ofstream(good) << sidecar_json().dump();
  EXPECT_EQ(camera_from_sidecar(good).source, "sidecar good.camera.json");
  expect_error([&] { camera_from_sidecar((dir / "none.camera.json").string()); }, Exit::input,
               {"none.camera.json"});
  fs::remove_all(dir);
}

// --------------------------------------------------------------------------------------
// Blender renders (tests/data/camera)

struct Render {
  int width = 0, height = 0;
  std::vector<Vec3> position;
  std::vector<float> depth;
  OIIO::ImageSpec spec;
};

Render read_render(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  Render r;
  r.spec = in->spec();
  r.width = r.spec.width;
  r.height = r.spec.height;
  const int nc = r.spec.nchannels;
  const int px = r.spec.channelindex("ViewLayer.Position.X");
  const int py = r.spec.channelindex("ViewLayer.Position.Y");
  const int pz = r.spec.channelindex("ViewLayer.Position.Z");
  const int dz = r.spec.channelindex("ViewLayer.Depth.Z");
  if (px < 0 || py < 0 || pz < 0 || dz < 0) throw std::runtime_error("passes missing: " + path);
  std::vector<float> pixels(size_t(r.width) * r.height * nc);
  if (!in->read_image(0, 0, 0, nc, OIIO::TypeFloat, pixels.data()))
    throw std::runtime_error(in->geterror());
  for (size_t i = 0; i < size_t(r.width) * r.height; ++i) {
    const float* p = &pixels[i * nc];
    r.position.push_back({p[px], p[py], p[pz]});
    r.depth.push_back(p[dz]);
  }
  return r;
}

bool is_background(const Vec3& p) {
  return p.x == 0 && p.y == 0 && p.z == 0;
}

class CameraBlenderRender : public ::testing::TestWithParam<std::string> {};

TEST_P(CameraBlenderRender, SidecarProjectsPositionOntoPixelCentres) {
  const std::string exr = kDataDir + GetParam() + ".exr";
  const Render r = read_render(exr);
  const Camera cam = camera_from_sidecar(sidecar_path_for(exr));
  ASSERT_EQ(cam.width, r.width);
  ASSERT_EQ(cam.height, r.height);
  double worst = 0, worst_depth_rel = 0;
  int n = 0;
  for (int row = 1; row + 1 < r.height; ++row) {
    for (int col = 1; col + 1 < r.width; ++col) {
      const size_t i = size_t(row) * r.width + col;
      // Interior pixels: the pixel and its 4-neighbours are foreground.
      if (is_background(r.position[i]) || is_background(r.position[i - 1]) ||
          is_background(r.position[i + 1]) || is_background(r.position[i - r.width]) ||
          is_background(r.position[i + r.width]))
        continue;
      const Vec3d v = cam.world_to_view(Vec3d(r.position[i]));
      ASSERT_GT(v.z, 0);
      double u, w;
      cam.project(v, u, w);
      worst = std::max(worst, std::hypot(u - (col + 0.5), w - (row + 0.5)));
      // Depth.Z is planar depth = view-space z.
      worst_depth_rel = std::max(worst_depth_rel, std::abs(r.depth[i] - v.z) / v.z);
      ++n;
    }
  }
  EXPECT_GT(n, 500);
  EXPECT_LT(worst, kSidecarReprojPx) << n << " interior pixels";
  EXPECT_LT(worst_depth_rel, 1e-5);
  RecordProperty("max_reprojection_px", std::to_string(worst));
}

TEST_P(CameraBlenderRender, SolvedCameraMatchesSidecar) {
  const std::string exr = kDataDir + GetParam() + ".exr";
  const Render r = read_render(exr);
  const Camera want = camera_from_sidecar(sidecar_path_for(exr));
  const Camera got = solve_camera_from_positions(r.width, r.height, r.position);
  EXPECT_LT(got.reprojection_rms_px, kSolvedRmsPx);
  expect_intrinsics_near(got, want, kSolvedIntrinsicsRel);
  EXPECT_LT(max_abs_diff(got.R, want.R), 1e-3);
  EXPECT_LT(length(got.centre() - want.centre()), 1e-3 * length(want.centre()));
  EXPECT_EQ(got.source.rfind("solved from Position (", 0), 0u) << got.source;
  // Blender writes no camera attributes: the caller must fall back.
  EXPECT_FALSE(camera_from_exr_attributes(r.spec).has_value());
  EXPECT_NE(camera_attribute_status(r.spec).find("no worldToCamera"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Cases, CameraBlenderRender,
                         ::testing::Values("auto_wide", "vertical", "auto_tall_aspect"));

// --------------------------------------------------------------------------------------
// Solver, synthetic

TEST(SolveCamera, SolvesAgainOnlyWhenPositionChanges) {
  const Camera want = test_camera();
  std::vector<Vec3> pos = positions_of(want, 1);
  const Camera a = solve_camera_from_positions(want.width, want.height, pos);
  const int solves = camera_solves();
  const Camera b = solve_camera_from_positions(want.width, want.height, pos);
  EXPECT_EQ(camera_solves(), solves);  // the same positions: the last camera, no solve
  EXPECT_EQ(a.fx, b.fx);
  EXPECT_EQ(a.cx, b.cx);
  EXPECT_EQ(a.t.x, b.t.x);
  EXPECT_EQ(a.source, b.source);
  for (Vec3& p : pos) p.x += 0.25f;  // the scene (or camera) moved
  const Camera c = solve_camera_from_positions(want.width, want.height, pos);
  EXPECT_EQ(camera_solves(), solves + 1);
  EXPECT_NE(c.t.x, a.t.x);
}

TEST(SolveCamera, RecoversKnownCameraNoiseFree) {
  const Camera want = test_camera();
  const Camera got = solve_camera_from_positions(want.width, want.height, positions_of(want, 1));
  expect_intrinsics_near(got, want, kNoiseFreeRel);
  EXPECT_NEAR(got.cx, want.cx, kNoiseFreeRel * want.cx);  // also relative to cx, cy
  EXPECT_NEAR(got.cy, want.cy, kNoiseFreeRel * want.cy);
  EXPECT_LT(max_abs_diff(got.R, want.R), 1e-6);
  EXPECT_LT(length(got.t - want.t), 1e-5);
  // float positions: the residual is float rounding, far below a pixel.
  EXPECT_LT(got.reprojection_rms_px, 1e-3);
  EXPECT_EQ(got.width, want.width);
  EXPECT_EQ(got.height, want.height);
}

TEST(SolveCamera, RejectsOutliersAndSilhouettes) {
  const Camera want = test_camera();
  std::vector<Vec3> pos = positions_of(want, 2);
  std::mt19937 rng(3);
  std::uniform_int_distribution<size_t> pick(0, pos.size() - 1);
  std::normal_distribution<float> kick(0, 0.5f);
  int spoiled = 0;
  for (int k = 0; k < 2000; ++k) {  // gross outliers: moved by ~0.5 scene units
    Vec3& p = pos[pick(rng)];
    if (is_background(p)) continue;
    p = p + Vec3(kick(rng), kick(rng), kick(rng));
    ++spoiled;
  }
  // Silhouette-like pixels: average of the pixel's point and its right neighbour's
  // (projects inside the pixel footprint, but not onto the centre).
  for (int k = 0; k < 1000; ++k) {
    const size_t i = pick(rng);
    if (i + 1 >= pos.size() || is_background(pos[i]) || is_background(pos[i + 1])) continue;
    pos[i] = (pos[i] + pos[i + 1]) * 0.5f;
  }
  const Camera got = solve_camera_from_positions(want.width, want.height, pos);
  expect_intrinsics_near(got, want, kNoiseFreeRel);
  EXPECT_LT(max_abs_diff(got.R, want.R), 1e-6);
  EXPECT_LT(got.reprojection_rms_px, 0.01);
  int n = 0;
  for (const Vec3& p : pos) n += !is_background(p);
  const int used = std::stoi(got.source.substr(got.source.find('(') + 1));
  // An even subset of at most kSolveMaxPixels takes part: of it, the share of clean pixels
  // (a kicked point may land near its own ray; a silhouette pixel may stay within tau).
  const double subset = std::min(n, kSolveMaxPixels);
  EXPECT_LE(used, subset * (n - spoiled + 20) / n + 100);
  EXPECT_GE(used, subset * (n - spoiled - 1000) / n - 100);
}

TEST(SolveCamera, ToleratesSubpixelJitter) {
  // Positions hit at random points of the pixel (a filtered or jittered Position pass):
  // the solve stays within 0.5 %, RMS about 0.4 px.
  const Camera want = test_camera();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> depth(2, 12), jitter(-0.5, 0.5);
  std::vector<Vec3> pos(size_t(want.width) * want.height);
  for (int row = 0; row < want.height; ++row)
    for (int col = 0; col < want.width; ++col) {
      const double u = col + 0.5 + jitter(rng), v = row + 0.5 + jitter(rng);
      pos[size_t(row) * want.width + col] =
          Vec3(want.view_to_world(want.unproject(u, v, depth(rng))));
    }
  const Camera got = solve_camera_from_positions(want.width, want.height, pos);
  expect_intrinsics_near(got, want, 0.005);
  EXPECT_NEAR(got.reprojection_rms_px, std::sqrt(2.0 / 12.0), 0.05);
}

TEST(SolveCamera, CoplanarPointsAreRefused) {
  const Camera want = test_camera();
  std::vector<Vec3> pos(size_t(want.width) * want.height);
  // Every pixel sees the world plane z = 0.5 (a floor).
  for (int row = 0; row < want.height; ++row)
    for (int col = 0; col < want.width; ++col) {
      const Vec3d o = want.centre();
      const Vec3d d = want.view_dir_to_world(want.unproject(col + 0.5, row + 0.5, 1));
      const double s = (0.5 - o.z) / d.z;
      if (s > 0) pos[size_t(row) * want.width + col] = Vec3(o + d * s);
    }
  expect_error([&] { solve_camera_from_positions(want.width, want.height, pos); }, Exit::camera,
               {"coplanar", "sidecar"});
}

TEST(SolveCamera, TooFewPixelsAreRefused) {
  const Camera want = test_camera();
  std::vector<Vec3> pos = positions_of(want, 5);
  int kept = 0;
  for (Vec3& p : pos) {
    if (is_background(p)) continue;
    if (++kept > 60) p = {};
  }
  pos[0] = {std::nanf(""), 1, 1};  // non-finite is background too
  expect_error([&] { solve_camera_from_positions(want.width, want.height, pos); }, Exit::camera,
               {"60", "sidecar"});
  expect_error([&] { solve_camera_from_positions(10, 10, pos); }, Exit::failure, {"10x10"});
}

// --------------------------------------------------------------------------------------
// EXR attributes worldToCamera / worldToNDC

// Row-vector product p * M with homogeneous divide.
Vec3d apply_row(const float* m, const Vec3d& p, double* w_out = nullptr) {
  double r[4];
  for (int j = 0; j < 4; ++j)
    r[j] = p.x * m[0 * 4 + j] + p.y * m[1 * 4 + j] + p.z * m[2 * 4 + j] + m[3 * 4 + j];
  if (w_out) *w_out = r[3];
  return {r[0] / r[3], r[1] / r[3], r[2] / r[3]};
}

// The matrices a renderer would write for `c`, built from the conventions directly:
// camera space (x right, y up, z forward) = (x, -y, z) of vision view space; NDC (0,0) top
// left, (1,1) bottom right: ndc = raster / (width, height).
void reference_matrices(const Camera& c, float wc[16], float wn[16]) {
  // p_cam = p * M: column j of the 3x3 block is row j of the world->camera rotation.
  const double flip[3] = {1, -1, 1};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) wc[i * 4 + j] = float(flip[j] * c.R.m[j][i]);
    wc[i * 4 + 3] = 0;
  }
  wc[12] = float(c.t.x), wc[13] = float(-c.t.y), wc[14] = float(c.t.z), wc[15] = 1;
  // ndc_x = (fx x/z + cx) / W, ndc_y = (fy (-y_c)/z + cy) / H, w = z.
  double proj[16] = {c.fx / c.width,
                     0,
                     0,
                     0,
                     0,
                     -c.fy / c.height,
                     0,
                     0,
                     c.cx / c.width,
                     c.cy / c.height,
                     0,
                     1,
                     0,
                     0,
                     1,
                     0};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += double(wc[i * 4 + k]) * proj[k * 4 + j];
      wn[i * 4 + j] = float(s);
    }
}

TEST(ExrCameraAttributes, ReadsReferenceMatrices) {
  const Camera want = test_camera();
  OIIO::ImageSpec spec(want.width, want.height, 3, OIIO::TypeFloat);
  EXPECT_FALSE(camera_from_exr_attributes(spec).has_value());
  EXPECT_NE(camera_attribute_status(spec).find("no worldToCamera"), std::string::npos);

  float wc[16], wn[16];
  reference_matrices(want, wc, wn);
  spec.attribute("worldtocamera", OIIO::TypeMatrix44, wc);
  EXPECT_FALSE(camera_from_exr_attributes(spec).has_value());
  EXPECT_NE(camera_attribute_status(spec).find("worldToNDC missing"), std::string::npos);

  spec.attribute("worldtoNDC", OIIO::TypeMatrix44, wn);
  const std::optional<Camera> got = camera_from_exr_attributes(spec);
  ASSERT_TRUE(got.has_value()) << camera_attribute_status(spec);
  expect_intrinsics_near(*got, want, 1e-5);
  EXPECT_LT(max_abs_diff(got->R, want.R), 1e-5);
  EXPECT_LT(length(got->t - want.t), 1e-5);
  EXPECT_NE(camera_attribute_status(spec).find("pinhole"), std::string::npos);

  // OpenEXR 3 also has double matrices (M44d).
  double dc[16], dn[16];
  for (int i = 0; i < 16; ++i) dc[i] = wc[i], dn[i] = wn[i];
  const OIIO::TypeDesc m44d(OIIO::TypeDesc::DOUBLE, OIIO::TypeDesc::MATRIX44);
  spec.attribute("worldtocamera", m44d, dc);
  spec.attribute("worldtoNDC", m44d, dn);
  const std::optional<Camera> from_double = camera_from_exr_attributes(spec);
  ASSERT_TRUE(from_double.has_value()) << camera_attribute_status(spec);
  EXPECT_DOUBLE_EQ(from_double->fx, got->fx);
}

TEST(ExrCameraAttributes, WrittenMatricesFollowTheConventions) {
  const Camera c = test_camera();
  OIIO::ImageSpec spec(c.width, c.height, 3, OIIO::TypeFloat);
  set_camera_attributes(spec, c);
  const OIIO::ParamValue* wc = spec.find_attribute("worldtocamera", OIIO::TypeMatrix44);
  const OIIO::ParamValue* wn = spec.find_attribute("worldtoNDC", OIIO::TypeMatrix44);
  ASSERT_TRUE(wc && wn);
  const float* mc = static_cast<const float*>(wc->data());
  const float* mn = static_cast<const float*>(wn->data());
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u01(0, 1);
  for (int k = 0; k < 100; ++k) {
    const double u = u01(rng) * c.width, v = u01(rng) * c.height, z = 1 + 10 * u01(rng);
    const Vec3d world = c.view_to_world(c.unproject(u, v, z));
    const Vec3d cam = apply_row(mc, world);  // left-handed, y up, z forward
    EXPECT_NEAR(cam.z, z, 1e-4);
    EXPECT_NEAR(cam.y, -c.unproject(u, v, z).y, 1e-4);
    const Vec3d ndc = apply_row(mn, world);
    EXPECT_NEAR(ndc.x * c.width, u, 1e-3);
    EXPECT_NEAR(ndc.y * c.height, v, 1e-3);
  }
}

TEST(ExrCameraAttributes, FileRoundTripWithDataWindow) {
  Camera want = test_camera();
  // Data window (8, 4) + 300x220 inside the 320x240 display window: the camera refers to
  // the data window, so its principal point moves by (-8, -4).
  OIIO::ImageSpec spec(300, 220, 1, OIIO::TypeFloat);
  spec.x = 8;
  spec.y = 4;
  spec.full_x = 0;
  spec.full_y = 0;
  spec.full_width = 320;
  spec.full_height = 240;
  Camera data_cam = want;
  data_cam.width = 300;
  data_cam.height = 220;
  data_cam.cx -= 8;
  data_cam.cy -= 4;
  set_camera_attributes(spec, data_cam);

  const fs::path path =
      fs::temp_directory_path() / ("hbil_camera_attr_" + std::to_string(::getpid()) + ".tmp.exr");
  {
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path.string(), spec));
    std::vector<float> pixels(300 * 220, 1.0f);
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, pixels.data()));
    out->close();
  }
  auto in = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(in);
  const OIIO::ImageSpec back = in->spec();
  in->close();
  fs::remove(path);
  const std::optional<Camera> got = camera_from_exr_attributes(back);
  ASSERT_TRUE(got.has_value()) << camera_attribute_status(back);
  EXPECT_EQ(got->width, 300);
  EXPECT_EQ(got->height, 220);
  expect_intrinsics_near(*got, data_cam, 1e-5);
  EXPECT_LT(max_abs_diff(got->R, want.R), 1e-5);
  EXPECT_LT(length(got->t - want.t), 1e-5);
}

TEST(ExrCameraAttributes, OrthographicIsNotAPinhole) {
  const Camera c = test_camera();
  OIIO::ImageSpec spec(c.width, c.height, 3, OIIO::TypeFloat);
  float wc[16], wn[16];
  reference_matrices(c, wc, wn);
  // Orthographic: ndc = (x_c / 10 + 0.5, -y_c / 10 + 0.5), w = 1.
  const float ortho[16] = {0.1f, 0, 0, 0, 0, -0.1f, 0, 0, 0, 0, 1, 0, 0.5f, 0.5f, 0, 1};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += double(wc[i * 4 + k]) * ortho[k * 4 + j];
      wn[i * 4 + j] = float(s);
    }
  spec.attribute("worldtocamera", OIIO::TypeMatrix44, wc);
  spec.attribute("worldtoNDC", OIIO::TypeMatrix44, wn);
  EXPECT_FALSE(camera_from_exr_attributes(spec).has_value());
  EXPECT_NE(camera_attribute_status(spec).find("not a perspective"), std::string::npos);
}

}  // namespace
}  // namespace hbil::io
