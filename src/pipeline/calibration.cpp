// calibration.cpp: see calibration.h.
#include "pipeline/calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <set>
#include <tuple>

#include "hbil/ao_frame.h"
#include "hbil/error.h"
#include "hbil/gbuffer.h"
#include "hbil/radiance_cache.h"
#include "hbil/reduced.h"
#include "io/exr_frame.h"
#include "io/layer_expr.h"
#include "pipeline/sequence_job.h"

namespace hbil::pipeline {

namespace {

// Sums of DiffCol x the search's irradiance (R + G + B) per tile of a cols x rows grid over
// g's display window, and the pixels of each (background adds 0 and counts).
void indirect_tiles(const ViewGBuffer& v, const GBuffer& g, const HorizonImage& h, int cols,
                    int rows, std::vector<double>& sums, std::vector<size_t>& counts) {
  sums.assign(size_t(cols) * size_t(rows), 0.0);
  counts.assign(sums.size(), 0);
  const int x0 = g.display_width > 0 ? g.display_x : 0, y0 = g.display_width > 0 ? g.display_y : 0;
  const int w = g.display_width > 0 ? g.display_width : g.width,
            hh = g.display_width > 0 ? g.display_height : g.height;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      if (!g.in_display(x, y)) continue;
      const int tx = std::min(cols - 1, (x - x0) * cols / w),
                ty = std::min(rows - 1, (y - y0) * rows / hh);
      const size_t t = size_t(ty) * size_t(cols) + size_t(tx);
      ++counts[t];
      const size_t i = size_t(y) * size_t(g.width) + size_t(x);
      if (v.is_background(i)) continue;
      const Vec3 a = g.diffcol[i], e = h.irradiance[i];
      sums[t] += double(a.x) * e.x + double(a.y) * e.y + double(a.z) * e.z;
    }
}

// The mean over g's display window of DiffCol x the search's irradiance (hbil's `indirect`),
// R + G + B; background adds 0. Summed in row order, the same for any thread count.
double indirect_mean(const ViewGBuffer& v, const GBuffer& g, const HorizonImage& h) {
  std::vector<double> sum;
  std::vector<size_t> n;
  indirect_tiles(v, g, h, 1, 1, sum, n);
  return n[0] ? sum[0] / double(n[0]) : 0.0;
}

// The grid of Params::calibration_tiles over a frame of w x h pixels computed and a render of
// `ref_pixels`: cols x rows with rows in proportion, at most one tile per 256 pixels of the
// render and per 64 of those computed. {0, 0}: off.
std::pair<int, int> tile_grid(int tiles, int w, int h, double ref_pixels) {
  for (int cols = tiles; cols >= 1; --cols) {
    const int rows = std::max(1, int(std::lround(double(cols) * h / std::max(w, 1))));
    const double n = double(cols) * rows;
    if (n * 256 <= ref_pixels && n * 64 <= double(w) * h) return {cols, rows};
  }
  return {0, 0};
}

// Frame c's point from its frame g (as the run reads it, colour packed or not) and camera.
CalibrationPoint solve_frame(const Params& p, const GBuffer& full, const Camera& full_cam, int c,
                             const std::string& path) {
  const auto t0 = std::chrono::steady_clock::now();
  CalibrationPoint pt;
  pt.frame = c;
  pt.path = path;
  // The grid of Params::calibration_tiles over the frame as computed (below), and the
  // render's mean over it and over each tile, in one reading.
  const int m = 2 * effective_search_scale(p, full.width, full.height);
  const int dw = std::max(1, (full.display_width > 0 ? full.display_width : full.width) / m),
            dh = std::max(1, (full.display_width > 0 ? full.display_height : full.height) / m);
  const ReferenceIndirect ref = reference_indirect(path, [&](double pixels) {
    return p.calibration_tiles > 0 ? tile_grid(p.calibration_tiles, dw, dh, pixels)
                                   : std::pair<int, int>{0, 0};
  });
  const std::pair<int, int> grid{ref.cols, ref.rows};
  pt.reference = ref.mean;
  // Frame c alone, computing what `indirect` needs, on one pixel in 2n x 2n where the run
  // searches one in n x n: a mean needs fewer pixels than an image.
  const std::pair<GBuffer, Camera> small = subsample(full, full_cam, m);
  const GBuffer& g = small.first;
  const Camera& cam = small.second;
  Params q = p;
  q.outputs = {"indirect"};
  q.temporal = false;
  q.search_scale = 1;
  std::optional<RadianceCache> pano;
  if (!q.panorama.empty()) {
    pano.emplace(1);
    pano->set_panorama(read_panorama(io::FramePattern(q.panorama).path(c), c, q),
                       float(q.background_depth), c);
  }
  const ViewGBuffer v = make_view_gbuffer(g, cam, q);
  // The temporal chain feeds each frame the indirect light of the frames before it, one more
  // bounce (Params::feedback). The solve stands in for it by feeding the frame its own indirect
  // light once: the mean the run reaches after a few frames, not the one its first frame has.
  const bool fed = p.temporal && p.feedback;
  // Every search of the solve is of the same view with the same parameters but for the fill's
  // level and the feedback: the first marches and records its gather, the others sum the
  // record with their own radiance and fill (the same results as marching again).
  GatherRecord record;
  // The tiles' sums without and with the fill (Params::calibration_tiles).
  std::vector<double> tiles_with, tiles_without;
  std::vector<size_t> tile_counts;
  std::vector<double>* tile_sums = nullptr;
  auto mean_at = [&](double s) {
    q.unseen_scale = s;
    HorizonImage h;
    for (int pass = 0; pass < (fed ? 2 : 1); ++pass) {
      FrameInputs fi;
      fi.frame = c;
      fi.cache = pano ? &*pano : nullptr;
      fi.record = &record;
      if (pass > 0) fi.feedback = std::move(h.irradiance);
      h = search_frame(v, g, cam, q, std::move(fi));
    }
    ++pt.solves;
    if (tile_sums && grid.first > 0)
      indirect_tiles(v, g, h, grid.first, grid.second, *tile_sums, tile_counts);
    return indirect_mean(v, g, h);
  };
  const double T = pt.reference;
  // The fill on first, so that the record holds the fill's share of every pixel.
  tile_sums = &tiles_with;
  pt.with = mean_at(1.0);
  tile_sums = &tiles_without;
  pt.without = mean_at(0.0);
  tile_sums = nullptr;
  double x0 = 0, f0 = pt.without - T, x1 = 1, f1 = pt.with - T;
  pt.reaches = pt.with - pt.without > 1e-6 * std::max(std::abs(pt.without), 1e-12);
  if (!pt.reaches) {
    pt.scale = 1;
  } else {
    auto secant = [&] { return std::clamp(x1 - f1 * (x1 - x0) / (f1 - f0), 0.0, kMaxScale); };
    double x = secant();
    // One bounce: the fill enters the gather linearly and the secant is exact.
    while (p.bounces > 1 && pt.solves < kMaxSolves) {
      const double fx = mean_at(x) - T;
      if (std::abs(fx) <= 1e-3 * std::abs(T) || fx == f1) break;
      x0 = x1, f0 = f1, x1 = x, f1 = fx;
      x = secant();
    }
    pt.scale = x;
    if (grid.first > 0 && pt.scale > 0) {
      const int cols = grid.first, rows = grid.second;
      FillTiles::View& t = pt.tiles;
      t.cam = cam;
      t.x0 = g.display_width > 0 ? g.display_x : 0;
      t.y0 = g.display_width > 0 ? g.display_y : 0;
      t.w = g.display_width > 0 ? g.display_width : g.width;
      t.h = g.display_width > 0 ? g.display_height : g.height;
      t.cols = cols;
      t.rows = rows;
      t.factor.assign(size_t(cols) * size_t(rows), 1.f);
      const double reach = pt.with - pt.without;  // the fill's share of the frame's mean
      // Each tile's factor as measured, r, and its variance from the render's noise (the
      // standard error of the tile's mean, through the linear solve).
      std::vector<double> r(t.factor.size(), 1.0), var(t.factor.size(), 0.0);
      std::vector<bool> solved(t.factor.size(), false);
      double spread = 0, noise = 0;
      size_t n_solved = 0;
      for (size_t k = 0; k < t.factor.size(); ++k) {
        if (tile_counts[k] == 0 || ref.counts[k] == 0) continue;
        const double n = double(tile_counts[k]), with = tiles_with[k] / n,
                     without = tiles_without[k] / n;
        if (!(with - without > 0) || !(with - without > kTileReach * reach)) continue;
        const double d = (with - without) * pt.scale;
        r[k] = (ref.tiles[k] - without) / d;
        var[k] = ref.se[k] * ref.se[k] / (d * d);
        if (!std::isfinite(r[k]) || !std::isfinite(var[k])) {  // beyond a double: left at 1
          r[k] = 1, var[k] = 0;
          continue;
        }
        r[k] = std::clamp(r[k], -kMaxScale, kMaxScale);  // the spread stays finite
        solved[k] = true;
        spread += (r[k] - 1) * (r[k] - 1);
        noise += var[k];
        ++n_solved;
      }
      // Shrunk towards the frame's factor by how much of their spread the noise explains
      // (empirical Bayes: the true factors' variance about 1 is what the measured ones have
      // beyond the noise's), so that a render too noisy to tell the tiles apart leaves them
      // at 1.
      const double tau2 = n_solved > 0 ? std::max(0.0, (spread - noise) / double(n_solved)) : 0.0;
      for (size_t k = 0; k < t.factor.size(); ++k) {
        if (!solved[k]) continue;
        const double keep = tau2 + var[k] > 0 ? tau2 / (tau2 + var[k]) : 0.0;
        t.factor[k] = float(std::clamp(1 + keep * (r[k] - 1), kMinTile, kMaxTile));
      }
    }
  }
  pt.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return pt;
}

// Of `sorted` (ascending), the nearest at or before `frame` and the nearest at or after it:
// one where they are the same or one is missing.
std::vector<int> bracket(const std::vector<int>& sorted, int frame) {
  std::vector<int> r;
  auto after = std::lower_bound(sorted.begin(), sorted.end(), frame);
  if ((after == sorted.end() || *after != frame) && after != sorted.begin())
    r.push_back(*std::prev(after));
  if (after != sorted.end()) r.push_back(*after);
  return r;
}

}  // namespace

std::pair<GBuffer, Camera> subsample(const GBuffer& g, const Camera& cam, int m) {
  if (m <= 1) {
    GBuffer copy = g;
    copy.unpack();
    return {std::move(copy), cam};
  }
  GBuffer s;
  s.width = std::max(1, g.width / m);
  s.height = std::max(1, g.height / m);
  const int k = m / 2;               // the pixel at each block's centre
  auto source = [&](int x, int y) {  // the index in g of pixel (x, y) of s
    return size_t(std::min(y * m + k, g.height - 1)) * size_t(g.width) +
           size_t(std::min(x * m + k, g.width - 1));
  };
  auto pick = [&](const auto& field, auto& out) {
    if (field.size() != g.pixels()) return;
    out.resize(s.pixels());
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) out[size_t(y) * s.width + x] = field[source(x, y)];
  };
  pick(g.depth, s.depth);
  pick(g.backdepth, s.backdepth);
  pick(g.normal, s.normal);
  pick(g.position, s.position);
  pick(g.alpha, s.alpha);
  pick(g.diffcol, s.diffcol);
  pick(g.diffdir, s.diffdir);
  pick(g.emit, s.emit);
  s.emit_gathered = g.emit_gathered;
  pick(g.f0, s.f0);
  pick(g.metallic, s.metallic);
  pick(g.escape, s.escape);
  for (const auto& [name, bits] : g.packed) {
    std::vector<Vec3>* out = s.rgb(name);
    if (!out || bits.size() != 3 * g.pixels()) continue;
    out->resize(s.pixels());
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) {
        const size_t i = 3 * source(x, y);
        (*out)[size_t(y) * s.width + x] =
            Vec3{half_to_float(bits[i]), half_to_float(bits[i + 1]), half_to_float(bits[i + 2])};
      }
  }
  // The display window: the pixels of s whose source pixel lies in g's.
  if (g.display_width > 0) {
    auto span = [&](int lo, int len, int n, int full) {  // [first, last] of s in [lo, lo + len)
      int a = n, b = -1;
      for (int x = 0; x < n; ++x) {
        const int sx = std::min(x * m + k, full - 1);
        if (sx >= lo && sx < lo + len) a = std::min(a, x), b = std::max(b, x);
      }
      return std::pair{a, b};
    };
    const auto [x0, x1] = span(g.display_x, g.display_width, s.width, g.width);
    const auto [y0, y1] = span(g.display_y, g.display_height, s.height, g.height);
    s.display_x = x0;
    s.display_y = y0;
    s.display_width = std::max(0, x1 - x0 + 1);
    s.display_height = std::max(0, y1 - y0 + 1);
    if (s.display_width == 0 || s.display_height == 0)  // no sample inside: keep every pixel
      s.display_width = s.display_height = 0;
  }
  // Pixel x of s is pixel m x + k of g, whose centre is at raster m (x + 0.5) + k + 0.5 − m / 2.
  Camera c = cam;
  const double shift = k + 0.5 - 0.5 * m;
  c.width = s.width;
  c.height = s.height;
  c.fx = cam.fx / m;
  c.fy = cam.fy / m;
  c.cx = (cam.cx - shift) / m;
  c.cy = (cam.cy - shift) / m;
  return {std::move(s), c};
}

namespace {

// Visits each pixel of the render's data window inside its display window with its DiffCol x
// DiffInd (R + G + B; non-finite products count as 0) and its place in the display window.
template <class Open, class F>
void for_each_reference_pixel(const std::string& path, Open&& open, F&& visit) {
  io::ImageFile im(path);
  const std::vector<int> col = io::layer_channels(im, "DiffCol"),
                         ind = io::layer_channels(im, "DiffInd");
  // R, G, B of each (a layer of one channel stands for all three); read in one pass over the
  // file.
  auto channel = [](const std::vector<int>& l, size_t k) { return l[std::min(k, l.size() - 1)]; };
  const size_t nc = 3;
  int lo = im.spec().nchannels, hi = 0;
  for (size_t k = 0; k < nc; ++k)
    for (const std::vector<int>* l : {&col, &ind})
      lo = std::min(lo, channel(*l, k)), hi = std::max(hi, channel(*l, k) + 1);
  const std::vector<float> px = im.read_range(lo, hi);
  // Over the pixels of the data window inside the display window (an overscan's guard band is
  // not the frame it calibrates), as hbil's own mean is taken.
  const OIIO::ImageSpec& sp = im.spec();
  const size_t stride = size_t(hi - lo);
  const int64_t w = std::min(sp.x + sp.width, sp.full_x + sp.full_width) -
                    std::max(sp.x, sp.full_x),
                h = std::min(sp.y + sp.height, sp.full_y + sp.full_height) -
                    std::max(sp.y, sp.full_y);
  open(double(std::max<int64_t>(w, 0)) * double(std::max<int64_t>(h, 0)));
  for (int y = std::max(sp.y, sp.full_y);
       y < std::min(sp.y + sp.height, sp.full_y + sp.full_height); ++y)
    for (int x = std::max(sp.x, sp.full_x);
         x < std::min(sp.x + sp.width, sp.full_x + sp.full_width); ++x) {
      const size_t i = size_t(y - sp.y) * size_t(sp.width) + size_t(x - sp.x);
      double sum = 0;
      for (size_t k = 0; k < nc; ++k) {
        const float v = px[i * stride + size_t(channel(col, k) - lo)] *
                        px[i * stride + size_t(channel(ind, k) - lo)];
        if (std::isfinite(v)) sum += v;
      }
      visit(x - sp.full_x, y - sp.full_y, sp.full_width, sp.full_height, sum);
    }
}

}  // namespace

ReferenceIndirect reference_indirect(const std::string& path,
                                     const std::function<std::pair<int, int>(double)>& grid) {
  ReferenceIndirect r;
  // Per tile: the sum, and the squared differences of pixels and their left neighbours in the
  // same tile, whose mean is twice the noise's variance per pixel where the light varies
  // smoothly (a render's noise, not its edges, which add a little).
  std::vector<double> diffs;
  std::vector<size_t> pairs;
  size_t n_tiles = 0, pixels = 0;
  double sum = 0, left = 0;
  int left_x = -2, left_y = -1;
  auto open = [&](double render_pixels) {
    std::tie(r.cols, r.rows) = grid(render_pixels);
    n_tiles = r.cols > 0 && r.rows > 0 ? size_t(r.cols) * size_t(r.rows) : 0;
    r.tiles.assign(n_tiles, 0.0);
    r.se.assign(n_tiles, 0.0);
    r.counts.assign(n_tiles, 0);
    diffs.assign(n_tiles, 0.0);
    pairs.assign(n_tiles, 0);
  };
  for_each_reference_pixel(path, open, [&](int x, int y, int w, int h, double v) {
    ++pixels;
    sum += v;
    if (n_tiles == 0) return;
    const int cols = r.cols, rows = r.rows;
    const int tx = std::min(cols - 1, int(int64_t(x) * cols / w)),
              ty = std::min(rows - 1, int(int64_t(y) * rows / h));
    const size_t t = size_t(ty) * size_t(cols) + size_t(tx);
    ++r.counts[t];
    r.tiles[t] += v;
    if (left_y == y && left_x == x - 1 &&
        std::min(cols - 1, int(int64_t(left_x) * cols / w)) == tx) {
      diffs[t] += (v - left) * (v - left);
      ++pairs[t];
    }
    left = v, left_x = x, left_y = y;
  });
  for (size_t t = 0; t < n_tiles; ++t) {
    if (r.counts[t] == 0) continue;
    r.tiles[t] /= double(r.counts[t]);
    if (pairs[t] > 0)
      r.se[t] = std::sqrt(diffs[t] / (2.0 * double(pairs[t])) / double(r.counts[t]));
  }
  r.mean = pixels > 0 ? sum / double(pixels) : 0.0;
  return r;
}

double reference_indirect_mean(const std::string& path) {
  return reference_indirect(path, [](double) { return std::pair<int, int>{0, 0}; }).mean;
}

std::string resolve_calibration(const std::string& calibration, const io::FramePattern& input) {
  if (calibration != "auto") return calibration;
  const std::filesystem::path in(input.text());
  const std::string beside = (in.parent_path() / "calibration" / in.filename()).string();
  const io::FramePattern cp(beside);
  // existing_frames() finds a sequence's files, and a single file where it is one; an
  // unreadable folder finds none.
  return cp.existing_frames().empty() ? std::string() : beside;
}

Calibration::Calibration(const Params& p, const io::FramePattern& input,
                         const std::vector<int>& frames)
    : pattern_(p.calibration) {
  const io::FramePattern cp(p.calibration);
  std::vector<int> on_disk;
  if (cp.is_sequence()) {
    on_disk = cp.existing_frames();
  } else if (std::filesystem::exists(cp.text())) {
    std::optional<int> f = io::frame_number_from_name(cp.text());
    if (!f) {
      const std::vector<int> shot = input.is_sequence() ? input.existing_frames() : frames;
      f = shot.empty() ? frames.front() : shot.front();
    }
    on_disk = {*f};
  }
  if (on_disk.empty()) throw Error(Exit::input, "calibration " + p.calibration + ": no file found");
  std::set<int> used;
  for (int f : frames)
    for (int c : bracket(on_disk, f)) used.insert(c);
  const std::vector<int> shot = input.is_sequence() ? input.existing_frames() : std::vector<int>{};
  for (int c : used) {
    const std::string path = cp.path(c);
    io::ImageFile im(path);  // Exit::input naming the file
    io::layer_channels(im, "DiffCol");
    io::layer_channels(im, "DiffInd");
    if (input.is_sequence() && !std::binary_search(shot.begin(), shot.end(), c))
      throw Error(Exit::input, "calibration " + path + " is frame " + std::to_string(c) +
                                   ", which the input " + input.text() + " does not have");
    frames_.push_back(c);
    paths_.push_back(path);
  }
}

std::vector<int> Calibration::around(int frame) const {
  return bracket(frames_, frame);
}

const std::string& Calibration::path(int c) const {
  auto it = std::lower_bound(frames_.begin(), frames_.end(), c);
  if (it == frames_.end() || *it != c)
    throw Error(Exit::failure, "calibration: frame " + std::to_string(c) + " is not planned");
  return paths_[size_t(it - frames_.begin())];
}

CalibrationPoint Calibration::solve(const Params& p, const GBuffer& g, const Camera& cam,
                                    int c) const {
  return solve_frame(p, g, cam, c, path(c));
}

CalibrationPoint Calibration::solve(const Params& p, const io::FramePattern& input, int c) const {
  const auto t0 = std::chrono::steady_clock::now();
  // The fields the run reads, so that both ways see the same frame.
  const io::InputFrame in = io::open_frame(input.path(c), c, p);
  GBuffer g = io::read_fields(in, io::fields_needed(in, p), p);
  const Camera cam = io::find_camera(in, g, p);
  CalibrationPoint pt = solve(p, g, cam, c);
  pt.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return pt;
}

std::vector<CalibrationPoint> Calibration::solve(const Params& p,
                                                 const io::FramePattern& input) const {
  std::vector<CalibrationPoint> points;
  for (int c : frames_) points.push_back(solve(p, input, c));
  return points;
}

FillTiles Calibration::tiles_at(const std::vector<CalibrationPoint>& points, int frame) {
  FillTiles out;
  auto add = [&](const CalibrationPoint& q, double w) {
    if (q.tiles.cols <= 0 || !(w > 0)) return;
    out.views.push_back(q.tiles);
    out.views.back().weight = w;
  };
  if (points.empty()) return out;
  if (frame <= points.front().frame) {
    add(points.front(), 1);
  } else if (frame >= points.back().frame) {
    add(points.back(), 1);
  } else {
    auto b = std::upper_bound(points.begin(), points.end(), frame,
                              [](int f, const CalibrationPoint& q) { return f < q.frame; });
    auto a = std::prev(b);
    const double t = double(frame - a->frame) / double(b->frame - a->frame);
    add(*a, 1 - t);
    add(*b, t);
  }
  return out;
}

double Calibration::scale_at(const std::vector<CalibrationPoint>& points, int frame) {
  if (points.empty()) return 1.0;
  if (frame <= points.front().frame) return points.front().scale;
  if (frame >= points.back().frame) return points.back().scale;
  auto b = std::upper_bound(points.begin(), points.end(), frame,
                            [](int f, const CalibrationPoint& q) { return f < q.frame; });
  auto a = std::prev(b);
  const double t = double(frame - a->frame) / double(b->frame - a->frame);
  return a->scale + t * (b->scale - a->scale);
}

}  // namespace hbil::pipeline
