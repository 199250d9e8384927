// calibration.cpp: see calibration.h.
#include "pipeline/calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <set>

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

// The mean over g's display window of DiffCol x the search's irradiance (hbil's `indirect`),
// R + G + B; background adds 0. Summed in row order, the same for any thread count.
double indirect_mean(const ViewGBuffer& v, const GBuffer& g, const HorizonImage& h) {
  double sum = 0;
  size_t n = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      if (!g.in_display(x, y)) continue;
      ++n;
      const size_t i = size_t(y) * size_t(g.width) + size_t(x);
      if (v.is_background(i)) continue;
      const Vec3 a = g.diffcol[i], e = h.irradiance[i];
      sum += double(a.x) * e.x + double(a.y) * e.y + double(a.z) * e.z;
    }
  return n ? sum / double(n) : 0.0;
}

// Frame c's point from its frame g (as the run reads it, colour packed or not) and camera.
CalibrationPoint solve_frame(const Params& p, const GBuffer& full, const Camera& full_cam, int c,
                             const std::string& path) {
  const auto t0 = std::chrono::steady_clock::now();
  CalibrationPoint pt;
  pt.frame = c;
  pt.path = path;
  pt.reference = reference_indirect_mean(path);
  // Frame c alone, computing what `indirect` needs, on one pixel in 2n x 2n where the run
  // searches one in n x n: a mean needs fewer pixels than an image.
  const std::pair<GBuffer, Camera> small =
      subsample(full, full_cam, 2 * effective_search_scale(p, full.width, full.height));
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
    return indirect_mean(v, g, h);
  };
  const double T = pt.reference;
  // The fill on first, so that the record holds the fill's share of every pixel.
  pt.with = mean_at(1.0);
  pt.without = mean_at(0.0);
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

double reference_indirect_mean(const std::string& path) {
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
  size_t pixels = 0;
  double sum = 0;
  for (int y = std::max(sp.y, sp.full_y);
       y < std::min(sp.y + sp.height, sp.full_y + sp.full_height); ++y)
    for (int x = std::max(sp.x, sp.full_x);
         x < std::min(sp.x + sp.width, sp.full_x + sp.full_width); ++x) {
      const size_t i = size_t(y - sp.y) * size_t(sp.width) + size_t(x - sp.x);
      ++pixels;
      for (size_t k = 0; k < nc; ++k) {
        const float v = px[i * stride + size_t(channel(col, k) - lo)] *
                        px[i * stride + size_t(channel(ind, k) - lo)];
        if (std::isfinite(v)) sum += v;
      }
    }
  return pixels > 0 ? sum / double(pixels) : 0.0;
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
