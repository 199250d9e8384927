// unseen_test.cpp: unseen_radiance "auto"'s escape model (unseen.h) against closed forms:
// the escape profile of frames whose background is known, the cosine-weighted escape over a
// hemisphere under an open upper half-space, and the fill map.
#include "hbil/unseen.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace hbil {
namespace {

constexpr int kBands = EscapeProfile::kBands;

// A level pinhole camera (principal point at the centre) over a w x h view whose pixels
// above row `sky_rows` are background and the others geometry with normal n.
struct Frame {
  Camera cam;
  ViewGBuffer v;
};
Frame frame(int w, int h, int sky_rows, Vec3 n = {0, 0, -1}) {
  Frame f;
  f.cam.width = w, f.cam.height = h;
  f.cam.fx = f.cam.fy = 0.8 * w;  // about 64 degrees across
  f.cam.cx = 0.5 * w, f.cam.cy = 0.5 * h;
  f.v.width = w, f.v.height = h;
  f.v.position.resize(f.v.pixels());
  f.v.normal.resize(f.v.pixels());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (y < sky_rows) {
        f.v.position[i] = Vec3{0, 0, std::numeric_limits<float>::infinity()};
      } else {
        f.v.position[i] = Vec3(f.cam.unproject(x + 0.5, y + 0.5, 2.0));
        f.v.normal[i] = n;
      }
    }
  return f;
}

Vec3 at_elevation(double e) {  // a unit view-space normal e above the horizontal (up is −y)
  return Vec3{float(std::cos(e)), float(-std::sin(e)), 0.f};
}

TEST(Unseen, AFrameOfGeometryEscapesNowhere) {
  const Frame f = frame(64, 36, 0);
  const EscapeProfile p = escape_profile(f.v, f.cam, true);
  for (int b = 0; b < kBands; ++b) EXPECT_EQ(p.open[size_t(b)], 0.f) << b;
  const EscapeTable t(p);
  for (double e : {-1.5, -0.7, 0.0, 0.7, 1.5}) EXPECT_EQ(t.at(at_elevation(e)), 0.f) << e;
}

TEST(Unseen, AFrameOfBackgroundEscapesEverywhere) {
  const Frame f = frame(64, 36, 36);
  const EscapeProfile p = escape_profile(f.v, f.cam, true);
  for (int b = 0; b < kBands; ++b) EXPECT_FLOAT_EQ(p.open[size_t(b)], 1.f) << b;
  const EscapeTable t(p);
  for (double e : {-1.5, -0.7, 0.0, 0.7, 1.5}) EXPECT_NEAR(t.at(at_elevation(e)), 1.f, 1e-6) << e;
}

// Sky above the horizon line, ground below, a level camera: the bands above the horizontal
// are open, those below closed, and the ones beyond the frame's 36-degree height carry the
// top and bottom bands' fractions.
TEST(Unseen, AnOpenSkyAboveTheHorizonOpensTheUpperBands) {
  const Frame f = frame(64, 36, 18);
  const EscapeProfile p = escape_profile(f.v, f.cam, true);
  for (int b = 0; b < kBands; ++b)
    EXPECT_FLOAT_EQ(p.open[size_t(b)], b >= kBands / 2 ? 1.f : 0.f) << b;
  // The frame reaches sin(elevation) ±0.33: bands 5 to 10.
  EXPECT_EQ(p.lowest_seen, 5);
  EXPECT_EQ(p.highest_seen, 10);
}

// By default (no carry) the bands the frame does not reach escape: a frame of geometry
// closes only the bands it shows (5 to 10 here, sin(elevation) −0.375 to 0.375).
TEST(Unseen, WithoutCarryTheBandsBeyondTheFrameEscape) {
  const Frame f = frame(64, 36, 0);
  const EscapeProfile p = escape_profile(f.v, f.cam, false);
  EXPECT_EQ(p.lowest_seen, 5);
  EXPECT_EQ(p.highest_seen, 10);
  for (int b = 0; b < kBands; ++b) EXPECT_EQ(p.open[size_t(b)], b >= 5 && b <= 10 ? 0.f : 1.f) << b;
  // Facing up, the hemisphere's cosine weight above sin(elevation) s is 1 − s²: the bands
  // from 11 (s = 6/16 · 2 − 1 = 0.375) up escape, 1 − 0.375²; facing down the same below −0.375.
  const EscapeTable t(p);
  EXPECT_NEAR(t.at(at_elevation(std::numbers::pi / 2)), 1 - 0.375 * 0.375, 2e-3);
  EXPECT_NEAR(t.at(at_elevation(-std::numbers::pi / 2)), 1 - 0.375 * 0.375, 2e-3);
  // With carry the same frame escapes nowhere; a frame that shows nothing escapes everywhere
  // without it and nowhere with it.
  for (float o : escape_profile(f.v, f.cam, true).open) EXPECT_EQ(o, 0.f);
  Frame none = frame(16, 9, 4);
  none.cam.fx = none.cam.fy = 0;
  for (float o : escape_profile(none.v, none.cam, false).open) EXPECT_EQ(o, 1.f);
}

// With carry, the frame's edges say what is beyond them. A frame of floor seen from above
// (every normal facing up) leaves the space above it open and closes the space below; a
// frame of ceiling the reverse; a frame of wall closes both (AFrameOfGeometryEscapesNowhere).
// A surface at 45 degrees, halfway along the ramp from 0.3 to 0.7 of its up component
// (sin 45° = 0.707 is just past it), opens its side fully; one tilted 30 degrees (up 0.5)
// half.
TEST(Unseen, WithCarryTheFramesEdgesSayWhatIsBeyondThem) {
  const Vec3 up{0, -1, 0}, down{0, 1, 0};
  for (const auto& [n, above, below] : {std::tuple{up, 1.f, 0.f},
                                        {down, 0.f, 1.f},
                                        {at_elevation(std::numbers::pi / 6), 0.5f, 0.f}}) {
    const Frame f = frame(64, 36, 0, n);
    const EscapeProfile p = escape_profile(f.v, f.cam, true);
    ASSERT_EQ(p.lowest_seen, 5);
    ASSERT_EQ(p.highest_seen, 10);
    for (int b = 0; b < kBands; ++b) {
      const float want = b > 10 ? above : b < 5 ? below : 0.f;
      EXPECT_NEAR(p.open[size_t(b)], want, 1e-5) << b << " up " << -n.y;
    }
    // Without carry the same frame escapes beyond its bands whatever it shows.
    const EscapeProfile q = escape_profile(f.v, f.cam, false);
    for (int b = 0; b < kBands; ++b) EXPECT_EQ(q.open[size_t(b)], b >= 5 && b <= 10 ? 0.f : 1.f);
  }
  // Sky over the top third of the rows: the top edge (2 of 36 rows) is all background, so
  // above the frame is open; the bottom edge is wall, so below it is closed.
  const Frame sky = frame(64, 36, 12);
  const EscapeProfile p = escape_profile(sky.v, sky.cam, true);
  EXPECT_EQ(p.open[size_t(kBands - 1)], 1.f);
  EXPECT_EQ(p.open[0], 0.f);
}

// Under an open upper half-space, the cosine-weighted fraction of a hemisphere above the
// horizontal is the sky view factor of a plane tilted from the zenith: (1 + sin e) / 2 for
// a normal at elevation e.
TEST(Unseen, TheHemispheresEscapeIsTheSkyViewFactor) {
  EscapeProfile p;
  for (int b = kBands / 2; b < kBands; ++b) p.open[size_t(b)] = 1.f;
  const EscapeTable t(p);
  for (double deg = -90; deg <= 90; deg += 7.5) {
    const double e = deg * std::numbers::pi / 180;
    EXPECT_NEAR(t.at(at_elevation(e)), (1 + std::sin(e)) / 2, 2e-3) << deg;
  }
  // Two open bands out of sixteen, straight up: a normal facing up sees them with weight
  // ∫ cos over the cap sin(elevation) > 0.75, that is 1 − 0.75² of the hemisphere.
  EscapeProfile cap;
  cap.open[kBands - 1] = cap.open[kBands - 2] = 1.f;
  EXPECT_NEAR(EscapeTable(cap).at(at_elevation(std::numbers::pi / 2)), 1 - 0.75 * 0.75, 2e-3);
}

// The fill map: fill x (1 − escape over the normal's hemisphere), nothing on background.
TEST(Unseen, TheFillMapDimsTheFillByTheEscape) {
  const Vec3 up{0, -1, 0};  // a ground plane's normal
  const Frame f = frame(64, 36, 18, up);
  const Vec3 fill{0.2f, 0.4f, 0.8f};
  const std::vector<Vec3> m = unseen_fill_map(f.v, escape_profile(f.v, f.cam, true), fill);
  ASSERT_EQ(m.size(), f.v.pixels());
  EXPECT_EQ(m[0].x, 0.f);  // sky
  const size_t ground = f.v.pixels() - 1;
  EXPECT_NEAR(m[ground].x, 0.f, 1e-3);  // facing the open sky: almost nothing
  const Frame wall = frame(64, 36, 18, Vec3{0, 0, -1});
  const std::vector<Vec3> mw =
      unseen_fill_map(wall.v, escape_profile(wall.v, wall.cam, true), fill);
  EXPECT_NEAR(mw[ground].z, 0.5f * fill.z, 2e-3);  // a wall: half its hemisphere is sky
  const Frame room = frame(64, 36, 0);
  const std::vector<Vec3> mr =
      unseen_fill_map(room.v, escape_profile(room.v, room.cam, true), fill);
  EXPECT_EQ(mr[ground].y, fill.y);  // walls to the frame's edges, enclosed: the whole fill
  // A frame of floor alone says nothing of what is above it: facing up, the bands above the
  // frame (sin(elevation) > 0.375) escape, 1 − 0.375² of the hemisphere's cosine weight.
  const Frame floor = frame(64, 36, 0, up);
  const std::vector<Vec3> mf =
      unseen_fill_map(floor.v, escape_profile(floor.v, floor.cam, true), fill);
  EXPECT_NEAR(mf[ground].y, 0.375f * 0.375f * fill.y, 2e-3);
}

// The escape pass at the searched pixels: a noisy 1-spp pass (0 or 1 per pixel) averages over
// each pixel's surface within kEscapeRadius, never across to another surface; the fill map
// gives the blocked share of the empty directions, 1 − e / a, and nothing where a <= e.
TEST(Unseen, TheEscapePassIsAveragedOverItsSurfaceAndDimsTheFill) {
  Frame f = frame(40, 20, 0);
  const int w = f.v.width, h = f.v.height;
  std::vector<float> e(f.v.pixels());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (x >= w / 2) {  // the right half: a second surface, twice as far, escaping everywhere
        f.v.position[i] = Vec3(f.cam.unproject(x + 0.5, y + 0.5, 4.0));
        e[i] = 1.f;
      } else {
        e[i] = float((x + y) % 2);  // a checkerboard of 0 and 1
      }
    }
  const std::vector<float> m = escape_at_view(f.v, f.v, 1, e, 0.05f);
  ASSERT_EQ(m.size(), f.v.pixels());
  const int r = kEscapeRadius, n = (2 * r + 1) * (2 * r + 1);  // a full window: 25 pixels
  for (int y = r; y < h - r; ++y)
    for (int x = r; x < w / 2 - r; ++x) {               // windows on the left surface alone
      const float ones = float(n / 2 + ((x + y) % 2));  // 12 or 13 ones among the 25
      EXPECT_FLOAT_EQ(m[size_t(y) * w + x], ones / float(n)) << x << " " << y;
    }
  for (int y = 0; y < h; ++y)  // the far surface's pixels see none of the near one's zeros
    EXPECT_EQ(m[size_t(y) * w + w / 2], 1.f) << y;
  // Reduced (f = 2): texel (i, j) is pixel (2i, 2j); the window is still 2 pixels.
  const ViewGBuffer lo = [&] {
    ViewGBuffer v;
    v.width = w / 2, v.height = h / 2;
    for (int j = 0; j < v.height; ++j)
      for (int i = 0; i < v.width; ++i) {
        v.position.push_back(f.v.position[size_t(2 * j) * w + 2 * i]);
        v.normal.push_back(f.v.normal[size_t(2 * j) * w + 2 * i]);
      }
    return v;
  }();
  const std::vector<float> ml = escape_at_view(f.v, lo, 2, e, 0.05f);
  EXPECT_FLOAT_EQ(ml[size_t(4) * lo.width + 4], m[size_t(8) * w + 8]);
  // The fill: e = 0.2 of the hemisphere escapes, the search leaves a open.
  const Vec3 fill{0.2f, 0.4f, 0.8f};
  const std::vector<float> esc(f.v.pixels(), 0.2f);
  std::vector<float> reach(f.v.pixels(), 0.8f);
  reach[1] = 0.1f;  // the search leaves less open than escapes: noise, no fill
  const std::vector<Vec3> fm = escape_fill_map(f.v, esc, reach, fill);
  EXPECT_FLOAT_EQ(fm[0].z, 0.75f * fill.z);  // 1 − 0.2 / 0.8
  EXPECT_EQ(fm[1].z, 0.f);
}

// Nothing the model is given ends outside its tables: a NaN normal reads as facing down in
// the table and as a wall at the frame's edges, a camera with no focal length counts nothing.
TEST(Unseen, NonFiniteInputsStayInTheTables) {
  EscapeProfile p;
  p.open[0] = 0.25f;  // straight down
  const EscapeTable t(p);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(t.at(Vec3{nan, nan, nan}), t.at(Vec3{0, 1, 0}));
  EXPECT_GT(t.at(Vec3{0, 1, 0}), 0.f);
  Frame f = frame(16, 9, 4);
  f.cam.fx = f.cam.fy = 0;
  const EscapeProfile none = escape_profile(f.v, f.cam, true);
  for (int b = 0; b < kBands; ++b) EXPECT_EQ(none.open[size_t(b)], 0.f) << b;
  // A frame of NaN normals with carry: walls at both edges, closed beyond them.
  const Frame bad = frame(64, 36, 0, Vec3{nan, nan, nan});
  for (float o : escape_profile(bad.v, bad.cam, true).open) EXPECT_EQ(o, 0.f);
}

}  // namespace
}  // namespace hbil
