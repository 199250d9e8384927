// radiance_cache_test.cpp: the radiance cache (radiance_cache.h): closed-form fills of a
// cache that knows the whole sphere, its window of frames, sky as known darkness, and the
// temporal chain unchanged by it where it knows nothing off screen.
#include "hbil/radiance_cache.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "analytic_scenes.h"
#include "hbil/ao_frame.h"
#include "hbil/temporal.h"
#include "test_util.h"

namespace hbil {
namespace {

constexpr double kPi = std::numbers::pi;

// How add_face adds its frame: as computed (add, its indirect light E), or ahead of its turn
// (add_ahead, without E), possibly with a cut.
enum class As { computed, ahead, ahead_cut };

// Frame `frame` of a camera at the origin looking along `axis` (90-degree field of view),
// inside a sphere of radius 5 whose surface sends radiance L0 (DiffCol 1, DiffDir L0 − E, E
// its indirect light: 0.25 when added as computed); with `sky`, nothing is there (every pixel
// background).
void add_face(RadianceCache& cache, const Vec3d& axis, int frame, float L0, bool sky = false,
              As as = As::computed) {
  const Vec3d up = std::fabs(axis.z) > 0.9 ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1};
  const Camera cam = test::look_at(48, 48, 90, {0, 0, 0}, axis, up);
  ViewGBuffer v;
  v.width = v.height = 48;
  v.position.resize(48 * 48);
  v.normal.resize(48 * 48);
  GBuffer g;
  g.width = g.height = 48;
  g.diffcol.assign(48 * 48, Vec3{1, 1, 1});
  const float E = as == As::computed ? 0.25f : 0.f;
  g.diffdir.assign(48 * 48, Vec3{L0 - E, L0 - E, L0 - E});
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x) {
      const Vec3d d = normalize_or_zero(cam.unproject(x + 0.5, y + 0.5, 1.0)) * 5.0;
      v.position[size_t(y) * 48 + x] = sky ? Vec3{0, 0, ViewGBuffer::kBackground * 2} : Vec3(d);
    }
  if (as == As::computed)
    cache.add(v, cam, g, std::vector<Vec3>(48 * 48, Vec3{E, E, E}), frame);
  else
    cache.add_ahead(v, cam, g, frame, as == As::ahead_cut);
}
void add_sphere(RadianceCache& cache, int frame, float L0, bool sky = false, As as = As::computed) {
  bool first = true;
  for (const Vec3d& a : {Vec3d{1, 0, 0}, Vec3d{-1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, -1, 0},
                         Vec3d{0, 0, 1}, Vec3d{0, 0, -1}}) {
    add_face(cache, a, frame, L0, sky, first ? as : as == As::ahead_cut ? As::ahead : as);
    first = false;
  }
}

// The frame that reads the cache: 60 degrees wide, looking along +y.
Camera reader() {
  return test::look_at(64, 36, 60, {0, 0, 0}, {0, 1, 0});
}

TEST(RadianceCache, ACacheThatKnowsEverySideGivesItsRadianceBehindTheCamera) {
  RadianceCache cache(8);
  add_sphere(cache, 3, 2.f);
  const Camera cam = reader();
  const std::vector<Vec3> table = cache.fill_table(cam, 4, Vec3{});
  // A normal facing the camera (view -z) sees off screen in nearly its whole hemisphere, all
  // of it known: F = L0 A / (A + ε) with A about π, ε = 0.05 π.
  const Vec3 back = RadianceCache::lookup(table, Vec3{0, 0, -1});
  EXPECT_NEAR(back.x, 2.0 / (1 + RadianceCache::kEpsilon), 0.02);
  EXPECT_FLOAT_EQ(back.x, back.y);
  // Sideways and up the same: the sphere is uniform.
  for (const Vec3& n : {Vec3{1, 0, 0}, Vec3{-1, 0, 0}, Vec3{0, -1, 0}}) {
    const Vec3 f = RadianceCache::lookup(table, n);
    EXPECT_GT(f.x, 1.85f) << n.x << " " << n.y << " " << n.z;
    EXPECT_LT(f.x, 2.0f);
  }
  // A normal along the view axis sees less off screen (the frustum is left out), so the
  // fallback (0) of ε weighs more, but what it sees is the sphere.
  const Vec3 ahead = RadianceCache::lookup(table, Vec3{0, 0, 1});
  EXPECT_GT(ahead.x, 1.5f);
  EXPECT_LT(ahead.x, back.x);
}

// A panorama of 64 x 32 pixels, equirectangular about world z, around a camera at the origin:
// a sphere of radius 4 with DiffCol rho and DiffDir D, its top half open (background) when
// `open_top`.
GBuffer panorama(float rho, float D, bool open_top) {
  GBuffer g;
  g.width = 64;
  g.height = 32;
  g.depth.assign(g.pixels(), 4.f);
  g.position.resize(g.pixels());
  g.diffcol.assign(g.pixels(), Vec3{rho, rho, rho});
  g.diffdir.assign(g.pixels(), Vec3{D, D, D});
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const double theta = (y + 0.5) / g.height * kPi, phi = (x + 0.5) / g.width * 2 * kPi;
      const size_t i = size_t(y) * g.width + x;
      g.position[i] = Vec3(
          Vec3d{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)} *
          4.0);
      if (open_top && y < g.height / 2) g.depth[i] = 1e10f;
    }
  return g;
}

TEST(RadianceCache, PanoramaAmbientIsTheEnclosuresEndlessBounces) {
  // Closed: mean direct 0.5 x 0.2 = 0.1 over the sphere, mean albedo 0.5: 0.1 / (1 - 0.5).
  EXPECT_NEAR(RadianceCache::panorama_ambient(panorama(0.5f, 0.2f, false), 1e9f).x, 0.2, 1e-5);
  // Half of the sphere open: both means halve, 0.05 / (1 - 0.25).
  EXPECT_NEAR(RadianceCache::panorama_ambient(panorama(0.5f, 0.2f, true), 1e9f).x, 0.05 / 0.75,
              1e-5);
  // Albedo 1 is held at kMaxAmbientAlbedo: finite.
  EXPECT_NEAR(RadianceCache::panorama_ambient(panorama(1.f, 0.2f, false), 1e9f).x,
              0.2 / (1 - RadianceCache::kMaxAmbientAlbedo), 1e-4);
}

TEST(RadianceCache, APanoramaLightsEveryNormalWithWhatItSees) {
  RadianceCache cache(1);
  EXPECT_TRUE(cache.empty());
  cache.set_panorama(panorama(0.5f, 0.2f, false), 1e9f, 7);
  EXPECT_FALSE(cache.empty());
  const Camera cam = reader();
  // Every direction, on screen too, holds L = rho (D + ambient) = 0.5 (0.2 + 0.2): each
  // normal's fill is L A / (A + ε) with A = π.
  const std::vector<Vec3> table = cache.fill_table(cam, 7, Vec3{});
  for (const Vec3& n : {Vec3{0, 0, 1}, Vec3{0, 0, -1}, Vec3{1, 0, 0}, Vec3{0, -1, 0}}) {
    const Vec3 f = RadianceCache::lookup(table, n);
    EXPECT_NEAR(f.x, 0.2 / (1 + RadianceCache::kEpsilon), 0.006) << n.x << n.y << n.z;
  }
  // Another frame does not read it; clear() (a cut) keeps it.
  EXPECT_FLOAT_EQ(RadianceCache::lookup(cache.fill_table(cam, 8, Vec3{1, 1, 1}), Vec3{0, 0, 1}).x,
                  1.f);
  cache.clear();
  EXPECT_NEAR(RadianceCache::lookup(cache.fill_table(cam, 7, Vec3{}), Vec3{0, 0, 1}).x,
              0.2 / (1 + RadianceCache::kEpsilon), 0.006);
  // Its open top half is unknown: it takes the fallback. An upward normal (view -y; the
  // reader looks along +y with z up) sees the open half only.
  cache.set_panorama(panorama(0.5f, 0.2f, true), 1e9f, 7);
  const Vec3 up =
      RadianceCache::lookup(cache.fill_table(cam, 7, Vec3{0.3f, 0.3f, 0.3f}), Vec3{0, -1, 0});
  EXPECT_NEAR(up.x, 0.3, 0.02);
}

TEST(RadianceCache, FramesOutsideItsWindowAreNotRead) {
  RadianceCache cache(8);
  add_sphere(cache, 3, 2.f);
  const Camera cam = reader();
  const Vec3 fb{0.25f, 0.5f, 0.75f};
  // Frame 3 itself and earlier frames do not read frame 3; frame 11 is 8 after it (reads
  // 3 .. 10), frame 12 no longer does.
  for (int frame : {2, 3, 12, 40}) {
    const Vec3 f = RadianceCache::lookup(cache.fill_table(cam, frame, fb), Vec3{0, 0, -1});
    EXPECT_FLOAT_EQ(f.x, fb.x) << frame;
    EXPECT_FLOAT_EQ(f.y, fb.y) << frame;
    EXPECT_FLOAT_EQ(f.z, fb.z) << frame;
  }
  EXPECT_GT(RadianceCache::lookup(cache.fill_table(cam, 11, fb), Vec3{0, 0, -1}).x, 1.5f);
  // Adding frame 20 drops what no later frame reads.
  add_face(cache, {0, 1, 0}, 20, 1.f);
  EXPECT_EQ(cache.size(), size_t(48 * 48));  // frame 20 alone, every pixel (48 < kColumns)
}

// Frames ahead: frame f reads those of f + 1 .. f + ahead that no cut separates from it, with
// their direct light alone; computing a frame replaces its entries ahead.
TEST(RadianceCache, FramesAheadAreReadWithinTheirWindowAndNotAcrossACut) {
  const Camera cam = reader();
  const Vec3 fb{0.25f, 0.5f, 0.75f};
  auto back = [&](const RadianceCache& c, int frame) {
    return RadianceCache::lookup(c.fill_table(cam, frame, fb), Vec3{0, 0, -1});
  };
  RadianceCache cache(0, 4);  // no earlier frame, 4 ahead
  add_sphere(cache, 6, 2.f, false, As::ahead);
  EXPECT_EQ(cache.size(), size_t(6 * 48 * 48));
  // Frames 2 .. 5 read frame 6; frame 6 itself, later ones and frame 1 (5 before) do not.
  for (int frame : {1, 6, 7})
    for (int ch = 0; ch < 3; ++ch) EXPECT_FLOAT_EQ(back(cache, frame)[ch], fb[ch]) << frame;
  for (int frame : {2, 5}) EXPECT_NEAR(back(cache, frame).x, 2.0 / 1.05, 0.02) << frame;
  // A cut at frame 4 (its frame all sky): frames 2 and 3 read neither frame 4 nor frame 6,
  // frames 4 and 5 read frame 6.
  RadianceCache cut(0, 4);
  add_sphere(cut, 4, 0.f, true, As::ahead_cut);
  add_sphere(cut, 6, 2.f, false, As::ahead);
  for (int frame : {2, 3})
    for (int ch = 0; ch < 3; ++ch) EXPECT_FLOAT_EQ(back(cut, frame)[ch], fb[ch]) << frame;
  EXPECT_NEAR(back(cut, 4).x, 2.0 / 1.05, 0.02);
  EXPECT_NEAR(back(cut, 5).x, 2.0 / 1.05, 0.02);
  // Computing frame 6 (its indirect light 0.25 on top of DiffDir 1.75) replaces its entries
  // ahead; a cache without earlier frames then holds none of them.
  RadianceCache computed(0, 4);
  add_sphere(computed, 6, 2.f, false, As::ahead);
  add_sphere(computed, 6, 2.f);
  EXPECT_EQ(computed.size(), 0u);
  // With earlier frames kept, frame 7 reads what frame 6 output: DiffDir 1.75 + E 0.25.
  RadianceCache both(8, 4);
  add_sphere(both, 6, 2.f, false, As::ahead);
  add_sphere(both, 6, 2.f);
  EXPECT_EQ(both.size(), size_t(6 * 48 * 48));
  EXPECT_NEAR(back(both, 7).x, 2.0 / 1.05, 0.02);
}

TEST(RadianceCache, SkyIsKnownDarkness) {
  RadianceCache cache(8);
  add_sphere(cache, 1, 0.f, /*sky=*/true);
  const Vec3 fb{1, 1, 1};
  const Vec3 f = RadianceCache::lookup(cache.fill_table(reader(), 2, fb), Vec3{0, 0, -1});
  // Only ε keeps the fallback: ε / (A + ε) with A about π.
  EXPECT_NEAR(f.x, RadianceCache::kEpsilon / (1 + RadianceCache::kEpsilon), 0.01);
}

// A fallback per pixel (the escape pass's fill) enters as a constant one does, each pixel's
// own times the unknown share of its normal; what the cache knows stays.
TEST(RadianceCache, APerPixelFallbackFillsOnlyTheUnknownShareOfItsPixel) {
  RadianceCache cache(8);
  add_face(cache, {0, -1, 0}, 3, 2.f);  // behind the reader (which looks along +y): known
  const Camera cam = reader();
  ViewGBuffer v;
  v.width = 3, v.height = 1;
  v.position.assign(3, Vec3{0, 0, 5});
  v.normal = {Vec3{0, 0, -1}, Vec3{1, 0, 0}, Vec3{0, -1, 0}};  // towards the camera, right, up
  for (const Vec3 fb : {Vec3{}, Vec3{0.5f, 1.f, 2.f}}) {
    const std::vector<Vec3> constant = cache.fill_map(v, cam, 4, fb);
    const std::vector<Vec3> per_pixel = cache.fill_map(v, cam, 4, std::vector<Vec3>(3, fb));
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_NEAR(per_pixel[i].x, constant[i].x, 1e-6 * (1 + constant[i].x)) << i;
      EXPECT_NEAR(per_pixel[i].z, constant[i].z, 1e-6 * (1 + constant[i].z)) << i;
    }
  }
  const std::vector<Vec3> zero = cache.fill_map(v, cam, 4, Vec3{});
  const std::vector<Vec3> one = cache.fill_map(v, cam, 4, Vec3{1, 1, 1});
  std::vector<Vec3> fb(3);
  fb[1] = Vec3{1, 1, 1};
  const std::vector<Vec3> mixed = cache.fill_map(v, cam, 4, fb);
  EXPECT_NEAR(mixed[0].x, zero[0].x, 1e-6);
  EXPECT_NEAR(mixed[1].x, one[1].x, 1e-6);
  EXPECT_NEAR(mixed[2].x, zero[2].x, 1e-6);
  // The normal towards the camera sees the known face behind it; the upward one less of it,
  // and more of the unknown.
  EXPECT_GT(zero[0].x, 0.5f);
  EXPECT_GT(one[2].x - zero[2].x, one[0].x - zero[0].x);
}

// The groove of temporal_test.cpp, seen by a camera turned `yaw` degrees; with `escape`, an
// escape pass (GBuffer::escape) of 0.3 over every pixel.
struct Scene {
  Camera cam;
  GBuffer g;
};
Scene groove(double yaw_deg, bool escape = false) {
  Scene s;
  s.g = test::lit_groove(s.cam, yaw_deg, 96, 96, 70);
  if (escape) s.g.escape.assign(s.g.pixels(), 0.3f);
  return s;
}
std::vector<AoFrame> run(const Params& p, double yaw_per_frame, int frames, bool escape = false) {
  TemporalChain chain(p);
  std::vector<AoFrame> out;
  int ahead = 1;  // the next frame to add ahead (radiance_cache_ahead), as the frame loop does
  for (int f = 1; f <= frames; ++f) {
    for (; ahead <= std::min(frames, f + p.radiance_cache_ahead); ++ahead) {
      const Scene a = groove(yaw_per_frame * (ahead - 1), escape);
      const Camera before = groove(yaw_per_frame * (ahead - 2), escape).cam;
      chain.look_ahead(a.g, a.cam, ahead, false, ahead > 1 ? &before : nullptr);
    }
    const Scene s = groove(yaw_per_frame * (f - 1), escape);
    out.push_back(chain.process(s.g, s.cam, f, false));
  }
  return out;
}

TEST(RadianceCache, AStaticCameraComputesWhatItDoesWithoutTheCache) {
  // With a constant fallback (through the marches' fill and the replay) and with "auto",
  // whose fill differs per normal.
  for (bool automatic : {false, true})
    for (bool vectorised : {true, false}) {
      Params p;
      p.outputs = {"ao", "irradiance"};
      p.unseen_radiance_auto = automatic;
      p.unseen_radiance = 0.5;
      p.bounces = 2;
      p.vectorised = vectorised;
      const std::vector<AoFrame> plain = run(p, 0, 4);
      // The frames before, and those ahead too.
      for (int ahead : {0, 2}) {
        p.radiance_cache = 8;
        p.radiance_cache_ahead = ahead;
        const std::vector<AoFrame> cached = run(p, 0, 4);
        for (size_t f = 0; f < plain.size(); ++f) {
          SCOPED_TRACE(std::to_string(f) + (vectorised ? " simd" : " scalar") +
                       (automatic ? " auto" : " 0.5") + " ahead " + std::to_string(ahead));
          test::expect_same_bytes(plain[f].irradiance, cached[f].irradiance, "irradiance");
          test::expect_same_bytes(plain[f].ao, cached[f].ao, "ao");
        }
      }
    }
}

// With the escape pass, where the cache knows nothing (a static camera: nothing off screen)
// each pixel keeps the pass's fill: the same bytes as without the cache.
TEST(RadianceCache, WithTheEscapePassAStaticCameraKeepsThePassesFill) {
  Params p;
  p.outputs = {"ao", "irradiance"};
  const std::vector<AoFrame> plain = run(p, 0, 4, true);
  p.radiance_cache = 8;
  const std::vector<AoFrame> cached = run(p, 0, 4, true);
  for (size_t f = 0; f < plain.size(); ++f) {
    SCOPED_TRACE(f);
    test::expect_same_bytes(plain[f].irradiance, cached[f].irradiance, "irradiance");
  }
  // The pass is used: without it, the frames differ.
  p.radiance_cache = 0;
  const std::vector<AoFrame> without = run(p, 0, 2, false);
  EXPECT_NE(std::memcmp(without[1].irradiance.data(), plain[1].irradiance.data(),
                        plain[1].irradiance.size() * sizeof(Vec3)),
            0);
}

// A camera at height 1 above a dark floor, looking level with a lit wall 3 behind it (DiffDir 1
// there) and turning 40 degrees a frame: the turn shows the wall from the fourth frame on.
Scene turning(int frame) {
  Scene s;
  const double yaw = 40.0 * (frame - 1) * kPi / 180;
  const Vec3d eye{0, 0, 1};
  s.cam = test::look_at(64, 48, 60, eye, eye + Vec3d{std::sin(yaw), std::cos(yaw), 0});
  s.g = test::ray_cast(s.cam, {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                               {{0, 0, 0}, {0, 0, 1}, {0, -1, 0}},
                               {{0, -3, 0}, {0, 1, 0}, {0, 0, 1}, 10}});
  s.g.diffcol.assign(s.g.pixels(), Vec3{0.8f, 0.8f, 0.8f});
  s.g.diffdir.assign(s.g.pixels(), Vec3{});
  for (size_t i = 0; i < s.g.pixels(); ++i)
    if (s.g.depth[i] < 1e9f && s.g.normal[i].y != 0) s.g.diffdir[i] = Vec3{1, 1, 1};
  return s;
}

// The first frame of that turn reads what the frames ahead show behind it: the floor, which
// finds nothing to gather on screen, receives the wall's light; its occlusion is unchanged.
// A cut given ahead, or found from a camera's jump, keeps the frames before it from reading
// past it.
TEST(RadianceCache, AFirstFrameReadsWhatTheFramesAheadShow) {
  Params p;
  p.outputs = {"ao", "irradiance"};
  p.unseen_radiance_auto = false;  // no fill: what leaves the frame is dark without the cache
  p.unseen_radiance = 0;
  auto energy = [](const AoFrame& f) {
    double e = 0;
    for (const Vec3& v : f.irradiance) e += v.x;
    return e;
  };
  const Scene s1 = turning(1);
  const AoFrame plain = TemporalChain(p).process(s1.g, s1.cam, 1, false);
  EXPECT_EQ(energy(plain), 0.0) << "the floor alone gathers nothing on screen";
  p.radiance_cache_ahead = 4;
  auto first_frame = [&](int cut_at, bool jump) {
    TemporalChain chain(p);
    for (int a = 2; a <= 5; ++a) {
      const Scene s = turning(a), before = turning(a - 1);
      const Camera far = test::look_at(64, 48, 60, {50, 0, 1}, {50, 1, 1});
      chain.look_ahead(s.g, s.cam, a, a == cut_at && !jump,
                       a == cut_at && jump ? &far : &before.cam);
    }
    return chain.process(s1.g, s1.cam, 1, false);
  };
  const AoFrame ahead = first_frame(0, false);
  test::expect_same_bytes(plain.ao, ahead.ao, "ao");
  EXPECT_GT(energy(ahead), 0.01 * double(ahead.irradiance.size()));
  // A cut at frame 4, given or a jump: frames 4 and 5 (which show the wall) are not read.
  for (bool jump : {false, true}) {
    const AoFrame cut = first_frame(4, jump);
    EXPECT_LT(energy(cut), 0.5 * energy(ahead)) << (jump ? "jump" : "given");
  }
}

TEST(RadianceCache, APlaneAloneReceivesTheFillOfItsNormal) {
  // A floor alone: the gather finds nothing in any direction, so every direction is unseen
  // and a pixel's irradiance (E/π, cosine-weighted mean radiance) is its fill: with the
  // cache's uniform sphere around the camera, F(n) of the table (fallback 0), in either
  // march and with the in-frame bounces' replay.
  const Camera cam = test::look_at(96, 54, 60, {0, -3, 1.5}, {0, 0, 0});
  GBuffer g = test::ray_cast(cam, {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 1e9}});
  g.diffcol.assign(g.pixels(), Vec3{0.5f, 0.5f, 0.5f});
  g.diffdir.assign(g.pixels(), Vec3{0.3f, 0.3f, 0.3f});
  RadianceCache cache(8);
  add_sphere(cache, 1, 2.f);
  const std::vector<Vec3> table = cache.fill_table(cam, 2, Vec3{});
  for (bool vectorised : {true, false})
    for (int bounces : {1, 2}) {
      Params p;
      p.outputs = {"ao", "irradiance"};
      p.vectorised = vectorised;
      p.bounces = bounces;
      const Params r = resolve_frame_outputs(g, p);
      const ViewGBuffer v = make_view_gbuffer(g, cam, r);
      FrameInputs in;
      in.frame = 2;
      in.cache = &cache;
      const HorizonImage h = search_frame(v, g, cam, r, in);
      size_t n = 0;
      for (size_t i = 0; i < v.pixels(); ++i) {
        if (v.is_background(i)) continue;
        const Vec3 f = RadianceCache::lookup(table, v.normal[i]);
        ASSERT_GT(f.x, 0.5f);
        // To the slices' quadrature of the hemisphere (16 directions a pixel): within 4 %.
        EXPECT_NEAR(h.irradiance[i].x / f.x, 1.0, 0.04) << i << " " << vectorised;
        ++n;
      }
      EXPECT_GT(n, v.pixels() / 3);
    }
}

}  // namespace
}  // namespace hbil
