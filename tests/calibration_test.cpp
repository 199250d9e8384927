// calibration_test.cpp: the unseen fill's level solved from a render with global illumination
// (pipeline/calibration.h): the factor found gives hbil's indirect light the render's mean,
// frames between calibration frames interpolate, and bad calibration renders fail by name.
#include "pipeline/calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "io/exr_frame.h"
#include "pipeline/sequence_job.h"
#include "test_util.h"

namespace hbil {
namespace {

using pipeline::Calibration;
using pipeline::CalibrationPoint;

const std::string kShot = test::kRoomPoles + "/frame_####.exr";

// A calibration render of w x h pixels: DiffCol 0.5 and DiffInd `ind` everywhere, so that its
// mean DiffCol x DiffInd, R + G + B, is 1.5 x ind.
void write_calibration(const std::string& path, float ind, bool with_diffind = true, int w = 64,
                       int h = 36) {
  std::vector<std::string> ch = {"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G",
                                 "ViewLayer.DiffCol.B"};
  if (with_diffind)
    ch.insert(ch.end(), {"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B"});
  test::write_exr(path, w, h, ch, [&](int, int, int c) { return c < 3 ? 0.5f : ind; });
}

// The defaults resolved on the shot's frame 1, as a run resolves them, with `calibration`.
Params resolved(const std::string& calibration, int bounces = 1) {
  Params p;
  p.calibration = calibration;
  p.bounces = bounces;
  p.temporal = false;  // no chain, no feedback: the solve computes the frame as it is
  return pipeline::SequenceJob(pipeline::plan_sequence(kShot, "1", 0, ""), p).params();
}

// hbil's `indirect` on what the calibration computes (frame 1, the centre pixel of every 2 x 2
// block), at unseen_scale s, through compute_ao_frame.
AoFrame small_frame(Params p, double s) {
  p.unseen_scale = s;
  p.search_scale = 1;
  p.temporal = false;
  const io::FramePattern shot(kShot);
  const io::InputFrame in = io::open_frame(shot.path(1), 1, p);
  GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
  const Camera cam = io::find_camera(in, g, p);
  const auto small = pipeline::subsample(g, cam, 2);
  return compute_ao_frame(small.first, small.second, p);
}

// hbil's `indirect` on frame 1 alone at unseen_scale s, on what the calibration computes (the
// centre pixel of every 2 x 2 block at this size): its mean over the pixels, R + G + B.
// Computed through compute_ao_frame and its `indirect` output, not the calibration's own sum.
double indirect_mean(Params p, double s) {
  const AoFrame f = small_frame(std::move(p), s);
  double sum = 0;
  for (const Vec3& e : f.indirect) sum += double(e.x) + e.y + e.z;
  return sum / double(f.indirect.size());
}

TEST(Calibration, TheFactorGivesTheRendersMean) {
  test::TempDir dir(test::test_name());
  const io::FramePattern shot(kShot);
  // A first solve tells hbil's means without and with the fill; the render is then made to
  // have the mean of the fill at 2.5 times its level.
  write_calibration(dir / "probe.exr", 0.1f);
  const Params p = resolved(dir / "probe.exr");
  const std::vector<CalibrationPoint> probe = Calibration(p, shot, {1}).solve(p, shot);
  ASSERT_EQ(probe.size(), 1u);
  EXPECT_NEAR(probe[0].reference, 0.15, 1e-6);
  ASSERT_TRUE(probe[0].reaches);
  ASSERT_GT(probe[0].with, probe[0].without * 1.05);  // the fill is a fair part of the light
  const double target = probe[0].without + 2.5 * (probe[0].with - probe[0].without);
  write_calibration(dir / "cal.exr", float(target / 1.5));
  const Params q = resolved(dir / "cal.exr");
  const std::vector<CalibrationPoint> c = Calibration(q, shot, {1}).solve(q, shot);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].frame, 1);   // a single file without a frame number: the shot's first frame
  EXPECT_EQ(c[0].solves, 2);  // one bounce: linear, one secant step
  EXPECT_NEAR(c[0].scale, 2.5, 1e-3);
  EXPECT_NEAR(indirect_mean(q, c[0].scale) / c[0].reference, 1.0, 1e-4);
  EXPECT_NEAR(indirect_mean(q, 0.0) / c[0].without, 1.0, 1e-4);
  // From the frame as a run holds it (colour as half bits), the same point to the bit.
  const io::InputFrame in = io::open_frame(shot.path(1), 1, q);
  GBuffer g = io::read_fields(in, io::fields_needed(in, q), q, true);
  ASSERT_FALSE(g.packed.empty());
  const Camera cam = io::find_camera(in, g, q);
  const CalibrationPoint held = Calibration(q, shot, {1}).solve(q, g, cam, 1);
  EXPECT_EQ(held.scale, c[0].scale);
  EXPECT_EQ(held.without, c[0].without);
  EXPECT_EQ(held.with, c[0].with);
  // With the temporal chain's feedback, the frame is computed a second time with its own
  // indirect light fed back: more light without the fill, still linear in the fill (one secant
  // step), and so a smaller factor.
  Params fed = q;
  fed.temporal = true;
  ASSERT_TRUE(fed.feedback);
  const CalibrationPoint f = Calibration(fed, shot, {1}).solve(fed, shot)[0];
  EXPECT_EQ(f.solves, 2);
  EXPECT_GT(f.without, c[0].without * 1.05);
  EXPECT_GT(f.with - f.without, (c[0].with - c[0].without) * 1.05);
  EXPECT_LT(f.scale, c[0].scale * 0.95);
  fed.feedback = false;  // a chain without feedback: the frame as it is
  EXPECT_EQ(Calibration(fed, shot, {1}).solve(fed, shot)[0].scale, c[0].scale);
}

// The solve searches its frame once and sums that search's record for its other levels and
// the feedback (FrameInputs::record): each search equals a new one to the bit, with the
// frame's own fill and with the escape pass's, with the record filled at another level.
TEST(Calibration, ARecordedSearchEqualsANewOneAtEveryLevel) {
  const io::FramePattern shot(kShot);
  for (const char* escape : {"", "AO"}) {
    SCOPED_TRACE(std::string("passes.escape \"") + escape + "\"");
    Params p = resolved("");
    p.passes["escape"] = escape;
    p.search_scale = 1;
    const io::InputFrame in = io::open_frame(shot.path(1), 1, p);
    GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
    ASSERT_EQ(g.escape.empty(), *escape == '\0');
    const Camera cam = io::find_camera(in, g, p);
    p = resolve_frame_outputs(g, p);
    ASSERT_TRUE(gathers(p));
    const ViewGBuffer v = make_view_gbuffer(g, cam, p);
    auto search = [&](double s, const std::vector<Vec3>& feedback, GatherRecord* record) {
      Params q = p;
      q.unseen_scale = s;
      FrameInputs fi;
      fi.frame = 1;
      fi.feedback = feedback;
      fi.record = record;
      return search_frame(v, g, cam, q, std::move(fi));
    };
    GatherRecord record;
    const HorizonImage first = search(1.0, {}, &record);
    ASSERT_TRUE(record.filled);
    const HorizonImage fed = search(1.0, first.irradiance, nullptr);
    const std::vector<Vec3> none;
    for (double s : {0.0, 0.5, 1.0, 3.0}) {
      SCOPED_TRACE("unseen_scale " + std::to_string(s));
      for (const std::vector<Vec3>* feedback : {&none, &fed.irradiance}) {
        const HorizonImage a = search(s, *feedback, nullptr), b = search(s, *feedback, &record);
        ASSERT_EQ(a.irradiance.size(), b.irradiance.size());
        EXPECT_EQ(std::memcmp(a.irradiance.data(), b.irradiance.data(),
                              a.irradiance.size() * sizeof(Vec3)),
                  0);
        EXPECT_EQ(std::memcmp(a.ao.data(), b.ao.data(), a.ao.size() * sizeof(float)), 0);
      }
    }
    // The fill reaches this frame: the levels differ.
    EXPECT_NE(std::memcmp(search(0.0, {}, &record).irradiance.data(), first.irradiance.data(),
                          first.irradiance.size() * sizeof(Vec3)),
              0);
  }
}

// The calibration computes on the pixel at the centre of every m x m block: its camera sees
// that pixel's ray, and its fields are that pixel's, colour kept as half bits unpacked.
TEST(Calibration, TheSubsampleSeesEachBlocksCentrePixel) {
  GBuffer g;
  g.width = 10, g.height = 6;
  g.depth.resize(g.pixels());
  g.normal.assign(g.pixels(), Vec3{0, 0, 1});
  for (size_t i = 0; i < g.pixels(); ++i) g.depth[i] = float(i);
  std::vector<std::uint16_t> bits(3 * g.pixels(), 0x3C00);  // 1.0
  bits[3 * (3 * 10 + 6) + 1] = 0x4000;                      // 2.0, green of pixel (6, 3)
  g.packed.emplace_back("diffcol", bits);
  Camera cam;
  cam.width = 10, cam.height = 6, cam.fx = 12, cam.fy = 11, cam.cx = 5.2, cam.cy = 2.9;
  for (int m : {2, 3}) {
    const auto [s, c] = pipeline::subsample(g, cam, m);
    ASSERT_EQ(s.width, 10 / m);
    ASSERT_EQ(s.height, 6 / m);
    EXPECT_EQ(c.width, s.width);
    const int k = m / 2;
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) {
        const int fx = m * x + k, fy = m * y + k;
        EXPECT_EQ(s.depth[size_t(y) * s.width + x], g.depth[size_t(fy) * 10 + fx]);
        const Vec3d a = c.unproject(x + 0.5, y + 0.5, 2.0),
                    b = cam.unproject(fx + 0.5, fy + 0.5, 2.0);
        EXPECT_NEAR(a.x, b.x, 1e-12);
        EXPECT_NEAR(a.y, b.y, 1e-12);
        EXPECT_EQ(s.diffcol[size_t(y) * s.width + x].y, fx == 6 && fy == 3 ? 2.0f : 1.0f);
      }
  }
  const auto [same, c1] = pipeline::subsample(g, cam, 1);
  EXPECT_EQ(same.depth, g.depth);
  EXPECT_EQ(same.diffcol.size(), g.pixels());
  EXPECT_EQ(c1.fx, cam.fx);
}

// An overscan's guard band is not the frame a calibration stands for: a render's mean is taken
// over its display window. 4 x 2 data pixels from x = -1, a 2 x 2 display window at the origin:
// DiffCol 0.5 x DiffInd 0.4 inside it (R + G + B: 0.6), DiffInd 100 in the band.
TEST(Calibration, TheRendersMeanIsOverItsDisplayWindow) {
  test::TempDir dir(test::test_name());
  test::Pixels px;
  px.spec = OIIO::ImageSpec(4, 2, 6, OIIO::TypeDesc::FLOAT);
  px.spec.channelnames = {"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B",
                          "ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B"};
  px.spec.x = -1;
  px.spec.full_x = 0, px.spec.full_y = 0, px.spec.full_width = 2, px.spec.full_height = 2;
  px.data.resize(4 * 2 * 6);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 6; ++c) px.at(x, y, c) = c < 3 ? 0.5f : (x == 1 || x == 2 ? 0.4f : 100.f);
  const std::string path = dir / "cal.exr";
  test::write_pixels(path, px);
  EXPECT_NEAR(pipeline::reference_indirect_mean(path), 0.6, 1e-6);
  // The same pixels with the display window the data window: the band counts.
  px.spec.full_x = -1, px.spec.full_width = 4;
  test::write_pixels(path, px);
  EXPECT_NEAR(pipeline::reference_indirect_mean(path), (4 * 0.6 + 4 * 150.0) / 8, 1e-4);
}

// hbil's own mean, over the shot frame's display window: the subsample keeps the pixels whose
// block centre lies inside it (10 x 6 data pixels, display window 5 x 4 at (3, 1)).
TEST(Calibration, TheSubsampleKeepsTheDisplayWindow) {
  GBuffer g;
  g.width = 10, g.height = 6;
  g.depth.assign(g.pixels(), 1.f);
  g.display_x = 3, g.display_y = 1, g.display_width = 5, g.display_height = 4;
  Camera cam;
  cam.width = 10, cam.height = 6, cam.fx = cam.fy = 10, cam.cx = 5, cam.cy = 3;
  const auto [s, c] = pipeline::subsample(g, cam, 2);  // centres at x 1, 3, 5, 7, 9; y 1, 3, 5
  EXPECT_EQ(s.display_x, 1);
  EXPECT_EQ(s.display_width, 3);  // x 3, 5, 7
  EXPECT_EQ(s.display_y, 0);
  EXPECT_EQ(s.display_height, 2);  // y 1, 3
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x)
      EXPECT_EQ(s.in_display(x, y), g.in_display(2 * x + 1, 2 * y + 1)) << x << ", " << y;
  const auto [whole, c1] = pipeline::subsample(g, cam, 1);
  EXPECT_EQ(whole.display_x, 3);
  EXPECT_EQ(whole.display_width, 5);
}

// With two bounces the fill lights the second bounce too: the secant is iterated until the
// means agree within 0.1 %.
TEST(Calibration, WithTwoBouncesTheSecantIsIterated) {
  test::TempDir dir(test::test_name());
  const io::FramePattern shot(kShot);
  write_calibration(dir / "probe.exr", 0.1f);
  const Params p = resolved(dir / "probe.exr", 2);
  const CalibrationPoint probe = Calibration(p, shot, {1}).solve(p, shot).at(0);
  const double target = probe.without + 3.0 * (probe.with - probe.without);
  write_calibration(dir / "cal.exr", float(target / 1.5));
  const Params q = resolved(dir / "cal.exr", 2);
  const CalibrationPoint c = Calibration(q, shot, {1}).solve(q, shot).at(0);
  EXPECT_GT(c.solves, 2);
  EXPECT_LE(c.solves, pipeline::kMaxSolves);
  EXPECT_GT(c.scale, 1.0);
  EXPECT_NEAR(indirect_mean(q, c.scale) / c.reference, 1.0, 1e-3);
}

// Per tile (Params::calibration_tiles), 4 columns: 4 x 2 tiles of 32 x 36 pixels, which a
// render of 128 x 72 (at most one tile per 256 of its pixels) allows. The renders are made at
// the computed pixels' resolution (DiffCol 1) from hbil's own indirect light at the fill's level
// 2.5, each pixel the mean of its tile (a render without noise):
//  - as it is, every tile takes the frame's factor;
//  - twice as bright on its right half, the left half's tiles keep 2.5 and the right half's
//    take the level at which each has the render's mean, to 1e-3 (one bounce, no history:
//    linear);
//  - as it is, each pixel off by +-60 % (a noisy render of the same light), the tiles' means
//    are off by a few per cent, which the noise explains: each factor is drawn to the frame's.
TEST(Calibration, EachTileTakesTheLevelOfItsOwnMean) {
  test::TempDir dir(test::test_name());
  const io::FramePattern shot(kShot);
  write_calibration(dir / "probe.exr", 0.1f);
  const Params p = resolved(dir / "probe.exr");
  ASSERT_EQ(p.calibration_tiles, 8);
  const AoFrame lo = small_frame(p, 0.0), hi = small_frame(p, 2.5);
  const int W = lo.width, H = lo.height, cols = 4, rows = 2;
  ASSERT_EQ(W, 128);
  ASSERT_EQ(H, 72);
  auto tile = [&](int x, int y) { return size_t(y * rows / H) * cols + size_t(x * cols / W); };
  auto sum3 = [](const Vec3& e) { return double(e.x) + e.y + e.z; };
  std::vector<Vec3d> mean(size_t(cols * rows));
  std::vector<double> l(mean.size()), h(mean.size());
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * size_t(W) + size_t(x), t = tile(x, y);
      mean[t] += Vec3d(hi.indirect[i]) / double(32 * 36);
      l[t] += sum3(lo.indirect[i]) / (32 * 36);
      h[t] += sum3(hi.indirect[i]) / (32 * 36);
    }
  // +-1 by pixel from a fixed hash: white noise, whose mean over a tile is a few per cent off.
  auto sign = [](int x, int y) {
    uint32_t k = uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u;
    k ^= k >> 13, k *= 0x5bd1e995u, k ^= k >> 15;
    return k & 1u ? 1.0 : -1.0;
  };
  const std::vector<std::string> ch = {"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G",
                                       "ViewLayer.DiffCol.B", "ViewLayer.DiffInd.R",
                                       "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B"};
  std::vector<double> written(mean.size());  // each tile's mean as written, R + G + B
  auto write = [&](const std::string& path, double right, double noise) {
    std::fill(written.begin(), written.end(), 0.0);
    test::write_exr(path, W, H, ch, [&](int x, int y, int c) {
      if (c < 3) return 1.f;
      const Vec3d e = mean[tile(x, y)];
      const float v = float((c == 3   ? e.x
                             : c == 4 ? e.y
                                      : e.z) *
                            (x >= W / 2 ? right : 1.0) * (1 + noise * sign(x, y)));
      written[tile(x, y)] += double(v) / (32 * 36);
      return v;
    });
  };
  auto solve = [&](const std::string& path) {
    Params q = resolved(path);
    q.calibration_tiles = cols;
    const CalibrationPoint c = Calibration(q, shot, {1}).solve(q, shot).at(0);
    EXPECT_EQ(c.tiles.cols, cols);
    EXPECT_EQ(c.tiles.rows, rows);  // 4 x 72 / 128 = 2.25, rounded
    EXPECT_EQ(c.tiles.factor.size(), mean.size());
    return c;
  };
  write(dir / "same.exr", 1.0, 0.0);
  const CalibrationPoint same = solve(dir / "same.exr");
  EXPECT_NEAR(same.scale, 2.5, 1e-3);
  for (float r : same.tiles.factor) EXPECT_NEAR(r, 1.0, 1e-3);

  write(dir / "right.exr", 2.0, 0.0);
  const CalibrationPoint c = solve(dir / "right.exr");
  EXPECT_GT(c.scale, 2.6);
  for (size_t t = 0; t < mean.size() && t < c.tiles.factor.size(); ++t) {
    const double r = c.tiles.factor[t], s_t = 2.5 * (written[t] - l[t]) / (h[t] - l[t]);
    ASSERT_GT((h[t] - l[t]) / 2.5, pipeline::kTileReach * (c.with - c.without)) << t;
    EXPECT_NEAR(r * c.scale / s_t, 1.0, 1e-3) << "tile " << t;
    if (t % cols < size_t(cols / 2)) EXPECT_NEAR(r * c.scale, 2.5, 2.5e-3) << "tile " << t;
  }
  // 8 columns ask for 40 tiles, more than the render's 36 of 256 pixels: 7 x 4.
  Params b = resolved(dir / "right.exr");
  EXPECT_EQ(Calibration(b, shot, {1}).solve(b, shot).at(0).tiles.cols, 7);

  write(dir / "noisy.exr", 1.0, 0.6);
  const CalibrationPoint n = solve(dir / "noisy.exr");
  double raw_off = 0, off = 0;
  for (size_t t = 0; t < mean.size() && t < n.tiles.factor.size(); ++t) {
    const double raw = 2.5 * (written[t] - l[t]) / (h[t] - l[t]) / n.scale;
    raw_off = std::max(raw_off, std::abs(raw - 1));
    off = std::max(off, std::abs(double(n.tiles.factor[t]) - 1));
  }
  EXPECT_GT(raw_off, 0.01);     // the noise moves the tiles' means
  EXPECT_LT(off, raw_off / 4);  // and the factors hardly
}

// The factor at a surface: its tile's seen from the calibration frame's camera, bilinear
// between tile centres, the views weighted, 1 where none sees it.
TEST(Calibration, ASurfaceTakesTheFactorOfItsTile) {
  FillTiles::View v;
  v.cam.width = 40, v.cam.height = 20;
  v.cam.fx = v.cam.fy = 20, v.cam.cx = 20, v.cam.cy = 10;  // identity pose: view = world
  v.w = 40, v.h = 20, v.cols = 4, v.rows = 2;
  v.factor = {1, 2, 3, 4, 5, 6, 7, 8};
  FillTiles t;
  t.views = {v};
  // Raster (u, r) at depth 1 is world ((u - 20) / 20, (r - 10) / 20, 1).
  auto at = [&](double u, double r) { return t.at(Vec3d((u - 20) / 20, (r - 10) / 20, 1)); };
  EXPECT_FLOAT_EQ(at(5, 5), 1.f);               // tile (0, 0)'s centre
  EXPECT_FLOAT_EQ(at(35, 15), 8.f);             // tile (3, 1)'s centre
  EXPECT_FLOAT_EQ(at(10, 5), 1.5f);             // half way to tile (1, 0)
  EXPECT_FLOAT_EQ(at(10, 10), 3.5f);            // and to the row below: (1 + 2 + 5 + 6) / 4
  EXPECT_FLOAT_EQ(at(1, 1), 1.f);               // beyond the outer centres: clamped
  EXPECT_FLOAT_EQ(at(41, 5), 1.f);              // outside the frame: no view sees it
  EXPECT_FLOAT_EQ(t.at(Vec3d(0, 0, -1)), 1.f);  // behind the camera
  // A second view, weighted 3 to the first's 1, that sees every point with factor 2.
  FillTiles::View w = v;
  w.factor.assign(8, 2.f);
  t.views[0].weight = 1;
  w.weight = 3;
  t.views.push_back(w);
  EXPECT_FLOAT_EQ(at(35, 15), (8.f + 3 * 2.f) / 4);
  EXPECT_FLOAT_EQ(at(41, 5), 1.f);
}

// Frame f's tiles are those of the calibration frames around it, weighted as its factor.
TEST(Calibration, FramesBetweenCalibrationFramesWeighTheirTiles) {
  std::vector<CalibrationPoint> pts(2);
  pts[0].frame = 2, pts[1].frame = 6;
  for (CalibrationPoint& q : pts) q.tiles.cols = q.tiles.rows = 1, q.tiles.factor = {1};
  auto weights = [&](int f) {
    std::vector<double> w;
    for (const FillTiles::View& v : Calibration::tiles_at(pts, f).views) w.push_back(v.weight);
    return w;
  };
  using W = std::vector<double>;
  EXPECT_EQ(weights(1), W{1.0});
  EXPECT_EQ(weights(3), (W{0.75, 0.25}));
  EXPECT_EQ(weights(6), W{1.0});
  EXPECT_EQ(weights(9), W{1.0});
  pts[1].tiles.cols = 0;  // a point without tiles (the fill reached nothing there)
  EXPECT_EQ(weights(3), W{0.75});
  EXPECT_TRUE(Calibration::tiles_at({}, 1).empty());
}

// A render darker than hbil's indirect light without any fill: the factor stops at 0.
TEST(Calibration, TheFactorIsClampedAtZero) {
  test::TempDir dir(test::test_name());
  const io::FramePattern shot(kShot);
  write_calibration(dir / "cal.exr", 0.0f);
  const Params p = resolved(dir / "cal.exr");
  const CalibrationPoint c = Calibration(p, shot, {1}).solve(p, shot).at(0);
  EXPECT_EQ(c.scale, 0.0);
}

TEST(Calibration, FramesBetweenCalibrationFramesInterpolate) {
  std::vector<CalibrationPoint> pts(2);
  pts[0].frame = 2, pts[0].scale = 2.0;
  pts[1].frame = 6, pts[1].scale = 4.0;
  EXPECT_EQ(Calibration::scale_at(pts, 0), 2.0);
  EXPECT_EQ(Calibration::scale_at(pts, 2), 2.0);
  EXPECT_EQ(Calibration::scale_at(pts, 3), 2.5);
  EXPECT_EQ(Calibration::scale_at(pts, 5), 3.5);
  EXPECT_EQ(Calibration::scale_at(pts, 6), 4.0);
  EXPECT_EQ(Calibration::scale_at(pts, 9), 4.0);
  EXPECT_EQ(Calibration::scale_at({pts[1]}, 1), 4.0);
  EXPECT_EQ(Calibration::scale_at({}, 1), 1.0);
}

// Only the calibration frames around the run's frames are solved, so that a chunk solves
// what it needs and uses the factors the whole run uses.
TEST(Calibration, OnlyTheCalibrationFramesAroundTheRunAreSolved) {
  test::TempDir dir(test::test_name());
  for (int f : {1, 4, 8}) write_calibration(dir / ("cal_000" + std::to_string(f) + ".exr"), 0.1f);
  Params p;
  p.calibration = dir / "cal_####.exr";
  const io::FramePattern shot(kShot);
  using V = std::vector<int>;
  EXPECT_EQ(Calibration(p, shot, {5, 6}).frames(), (V{4, 8}));
  EXPECT_EQ(Calibration(p, shot, {4}).frames(), (V{4}));
  EXPECT_EQ(Calibration(p, shot, {1, 2}).frames(), (V{1, 4}));
  EXPECT_EQ(Calibration(p, shot, {1, 2, 3, 4, 5, 6, 7, 8}).frames(), (V{1, 4, 8}));
}

TEST(Calibration, BadCalibrationRendersFailByName) {
  test::TempDir dir(test::test_name());
  const io::FramePattern shot(kShot);
  Params p;
  write_calibration(dir / "cal_0001.exr", 0.1f, false);
  p.calibration = dir / "cal_####.exr";
  test::expect_error([&] { Calibration(p, shot, {1}); }, Exit::missing_pass,
                     {dir / "cal_0001.exr", "DiffInd"});
  p.calibration = dir / "none_####.exr";
  test::expect_error([&] { Calibration(p, shot, {1}); }, Exit::input,
                     {dir / "none_####.exr", "no file found"});
  write_calibration(dir / "late_0009.exr", 0.1f);
  p.calibration = dir / "late_####.exr";
  test::expect_error([&] { Calibration(p, shot, {8}); }, Exit::input,
                     {dir / "late_0009.exr", "frame 9", "does not have"});
}

// The command line: a run calibrated on a render of the shot brings its indirect light to the
// render's mean, says what it found, and a chunk computes what the whole run does.
TEST(Calibration, ARunTakesTheRendersMean) {
  test::TempDir dir(test::test_name());
  const std::string ref = test::kRoomPoles + "/frame_0001.exr";
  auto mean = [](const std::string& path, const std::string& layer, const std::string& times) {
    const test::Pixels px = test::read_pixels(path);
    double sum = 0;
    for (const char* c : {".R", ".G", ".B"}) {
      const int k = px.channel(layer + c), t = times.empty() ? -1 : px.channel(times + c);
      EXPECT_GE(k, 0) << layer << c;
      for (int y = 0; y < px.spec.height; ++y)
        for (int x = 0; x < px.spec.width; ++x)
          sum += double(px.at(x, y, k)) * (t < 0 ? 1.0 : px.at(x, y, t));
    }
    return sum / (double(px.spec.width) * px.spec.height);
  };
  const double target = mean(ref, "ViewLayer.DiffInd", "ViewLayer.DiffCol");
  const std::string set = " --no-display --set 'outputs=[\"indirect\"]'";
  // A frame alone (no temporal chain, so no feedback): the solve computes what the run does.
  const test::RunResult plain = test::run_hbil(
      "run " + test::q(ref) + " -o " + test::q(dir / "a.exr") + set + " --set temporal=false",
      dir.path());
  ASSERT_EQ(plain.code, 0) << plain.err;
  const test::RunResult cal =
      test::run_hbil("run " + test::q(ref) + " -o " + test::q(dir / "b.exr") + set +
                         " --set temporal=false --set calibration=" + test::q(ref) +
                         " --log-json " + test::q(dir / "log.jsonl"),
                     dir.path());
  ASSERT_EQ(cal.code, 0) << cal.err;
  EXPECT_TRUE(test::contains(cal.err, "calibration, frame 1: unseen_scale")) << cal.err;
  // The log for machines has the factor and both means.
  bool logged = false;
  std::istringstream lines(test::read_text(dir / "log.jsonl"));
  for (std::string line; std::getline(lines, line);) {
    const nlohmann::json j = nlohmann::json::parse(line);
    if (j["event"] != "calibration") continue;
    logged = true;
    EXPECT_EQ(j["frame"], 1);
    EXPECT_EQ(j["file"], ref);
    EXPECT_GT(j["unseen_scale"].get<double>(), 0.0);
    EXPECT_GT(j["mean_with_fill"].get<double>(), j["mean_without_fill"].get<double>());
    EXPECT_NEAR(j["reference_mean"].get<double>() / target, 1.0, 1e-6);
  }
  EXPECT_TRUE(logged);
  const double before = mean(dir / "a.exr", "indirect", ""),
               after = mean(dir / "b.exr", "indirect", "");
  // The run searches every pixel, the calibration one in 2 x 2: their means differ a little.
  EXPECT_NEAR(after / target, 1.0, 0.02) << before << " " << after << " " << target;
  EXPECT_GT(std::abs(before / target - 1.0), 0.1) << before << " " << target;

  // The same frame alone through the temporal chain: a run of one frame has no history to
  // feed back, so the factor is solved as for a frame alone, and gives the same mean.
  const test::RunResult one =
      test::run_hbil("run " + test::q(ref) + " -o " + test::q(dir / "c.exr") + set +
                         " --set calibration=" + test::q(ref),
                     dir.path());
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_NEAR(mean(dir / "c.exr", "indirect", "") / target, 1.0, 0.02);

  // A calibration render without DiffInd: exit 4 naming it, before any frame is written.
  write_calibration(dir / "bad.exr", 0.1f, false);
  const test::RunResult bad = test::run_hbil("run " + test::q(kShot) + " --frames 1-2 -o " +
                                                 test::q(dir / "bad/f_####.exr") + set +
                                                 " --set calibration=" + test::q(dir / "bad.exr"),
                                             dir.path());
  EXPECT_EQ(bad.code, int(Exit::missing_pass)) << bad.err;
  EXPECT_TRUE(test::contains(bad.err, dir / "bad.exr")) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad")) << "nothing is written";

  // Through the temporal chain, calibrated on every frame (the sample carries DiffInd): the
  // solve feeds each frame its own indirect light once, standing in for the chain's feedback,
  // so that once the chain has a history its frames have their renders' means. (Solved
  // without that feedback, frames 5-8 come out 12-13 % too bright.)
  const test::RunResult chain =
      test::run_hbil("run " + test::q(kShot) + " -o " + test::q(dir / "chain/f_####.exr") + set +
                         " --set calibration=" + test::q(kShot),
                     dir.path());
  ASSERT_EQ(chain.code, 0) << chain.err;
  for (int f = 5; f <= 8; ++f) {
    const std::string name = "/frame_000" + std::to_string(f) + ".exr";
    const std::string out = "chain/f_000" + std::to_string(f) + ".exr";
    const double want = mean(test::kRoomPoles + name, "ViewLayer.DiffInd", "ViewLayer.DiffCol");
    EXPECT_NEAR(mean(dir / out, "indirect", "") / want, 1.0, 0.03) << "frame " << f;
  }

  // Calibration frames 1 and 4: frames 2 and 3 interpolate, in a chunk as in the whole run.
  write_calibration(dir / "cal_0001.exr", 0.2f);
  write_calibration(dir / "cal_0004.exr", 0.4f);
  const std::string seq =
      " --set temporal=false --set calibration=" + test::q(dir / "cal_####.exr");
  ASSERT_EQ(test::run_hbil("run " + test::q(kShot) + " --frames 1-4 -o " +
                               test::q(dir / "whole/f_####.exr") + set + seq,
                           dir.path())
                .code,
            0);
  const test::RunResult chunk = test::run_hbil(
      "run " + test::q(kShot) + " --frames 2-3 -o " + test::q(dir / "chunk/f_####.exr") + set + seq,
      dir.path());
  ASSERT_EQ(chunk.code, 0) << chunk.err;
  EXPECT_TRUE(test::contains(chunk.err, "calibration, frame 1:")) << chunk.err;
  EXPECT_TRUE(test::contains(chunk.err, "calibration, frame 4:")) << chunk.err;
  for (int f : {2, 3}) {
    const std::string name = "/f_000" + std::to_string(f) + ".exr";
    const test::Pixels a = test::read_pixels(dir / ("whole" + name)),
                       b = test::read_pixels(dir / ("chunk" + name));
    EXPECT_EQ(a.spec.channelnames, b.spec.channelnames);
    EXPECT_TRUE(a.data == b.data) << "frame " << f;
  }
}

// calibration "auto" (the default): the input's own file names in calibration/ beside its
// frames, where any exists; a run that finds them is the run given them explicitly, and one
// that finds none is the run without calibration.
TEST(Calibration, AutoFindsTheRendersBesideTheFrames) {
  namespace fs = std::filesystem;
  test::TempDir dir(test::test_name());
  fs::create_directories(dir / "shot");
  for (const char* f :
       {"frame_0001.exr", "frame_0002.exr", "frame_0001.camera.json", "frame_0002.camera.json"})
    fs::create_symlink(test::kRoomPoles + "/" + f, dir / ("shot/" + std::string(f)));
  const io::FramePattern shot(dir / "shot/frame_####.exr");
  EXPECT_EQ(pipeline::resolve_calibration("auto", shot), "");
  EXPECT_EQ(pipeline::resolve_calibration("", shot), "");
  EXPECT_EQ(pipeline::resolve_calibration("cal/f_####.exr", shot), "cal/f_####.exr");

  const std::string set = " --no-display --set 'outputs=[\"indirect\"]' --set temporal=false";
  auto run = [&](const std::string& out, const std::string& extra) {
    const test::RunResult r = test::run_hbil(
        "run " + test::q(shot.text()) + " -o " + test::q(dir / (out + "/f_####.exr")) + set + extra,
        dir.path());
    EXPECT_EQ(r.code, 0) << r.err;
    return r;
  };
  // None there: the default run is the run without calibration.
  const test::RunResult none = run("none", "");
  EXPECT_FALSE(test::contains(none.err, "calibration")) << none.err;
  run("off", " --set calibration=");

  fs::create_directories(dir / "shot/calibration");
  write_calibration(dir / "shot/calibration/frame_0001.exr", 0.2f);
  const std::string beside = dir / "shot/calibration/frame_####.exr";
  EXPECT_EQ(pipeline::resolve_calibration("auto", shot), beside);
  EXPECT_EQ(pipeline::resolve_calibration("auto", io::FramePattern(dir / "shot/frame_0001.exr")),
            dir / "shot/calibration/frame_0001.exr");
  EXPECT_EQ(pipeline::resolve_calibration("auto", io::FramePattern(dir / "shot/frame_0002.exr")),
            "");
  // hbil info says what a run of each frame finds.
  const test::RunResult info1 =
      test::run_hbil("info " + test::q(dir / "shot/frame_0001.exr"), dir.path());
  EXPECT_TRUE(test::contains(
      info1.out, "calibration: auto = " + std::string(dir / "shot/calibration/frame_0001.exr")))
      << info1.out;
  const test::RunResult info2 =
      test::run_hbil("info " + test::q(dir / "shot/frame_0002.exr"), dir.path());
  EXPECT_TRUE(test::contains(info2.out, "calibration: auto = none")) << info2.out;
  const test::RunResult found = run("auto", "");
  EXPECT_TRUE(test::contains(found.err, "calibration auto: " + beside)) << found.err;
  EXPECT_TRUE(test::contains(found.err, "calibration, frame 1: unseen_scale")) << found.err;
  run("given", " --set calibration=" + test::q(beside));
  run("stillnone", " --set calibration=");
  for (const char* f : {"/f_0001.exr", "/f_0002.exr"}) {
    const test::Pixels a = test::read_pixels(dir / ("auto" + std::string(f))),
                       b = test::read_pixels(dir / ("given" + std::string(f))),
                       c = test::read_pixels(dir / ("none" + std::string(f))),
                       d = test::read_pixels(dir / ("off" + std::string(f))),
                       e = test::read_pixels(dir / ("stillnone" + std::string(f)));
    EXPECT_TRUE(a.data == b.data) << f;
    EXPECT_TRUE(c.data == d.data) << f;
    EXPECT_TRUE(c.data == e.data) << f;
    EXPECT_FALSE(a.data == c.data) << f << ": the render's level differs from the default's";
  }
  // unseen_carry "auto": on with the calibration found, off without; each file's preset says so.
  auto preset = [&](const std::string& out) {
    const test::Pixels px = test::read_pixels(dir / (out + "/f_0001.exr"));
    return nlohmann::json::parse(px.spec.get_string_attribute("hbil:preset"));
  };
  EXPECT_EQ(preset("auto")["unseen_carry"], true);
  EXPECT_EQ(preset("auto")["calibration"], beside);
  EXPECT_EQ(preset("none")["unseen_carry"], false);
  EXPECT_EQ(preset("none")["calibration"], "");
  // Given false, it stays off with the calibration: not the run with it on.
  run("nocarry", " --set unseen_carry=false");
  EXPECT_EQ(preset("nocarry")["unseen_carry"], false);
  EXPECT_FALSE(test::read_pixels(dir / "nocarry/f_0001.exr").data ==
               test::read_pixels(dir / "auto/f_0001.exr").data);
}

}  // namespace
}  // namespace hbil
