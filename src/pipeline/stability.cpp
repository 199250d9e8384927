// stability.cpp: see stability.h.
#include "pipeline/stability.h"

#include <OpenImageIO/imagebuf.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>

#include "hbil/error.h"
#include "io/camera_io.h"
#include "io/exr_output.h"
#include "pipeline/sequence_job.h"

namespace hbil::pipeline {

namespace fs = std::filesystem;

namespace {

constexpr int kStaticFrames = 6, kCutFrames = 6;
constexpr double kEdgeBand = 0.05, kThinRise = 0.10, kRecovered = 1e-3;
constexpr int kThinPixels = 3;  // on each side: objects up to 6 pixels across

// The channels of a computed frame, as planes, whose name `keep` accepts.
std::vector<std::vector<float>> planes(const FrameResult& fr, const Params& p,
                                       const std::function<bool(const std::string&)>& keep) {
  std::vector<std::vector<float>> out;
  const size_t n = size_t(fr.outputs.width) * fr.outputs.height;
  for (const io::OutputChannel& oc : io::output_plan(fr.outputs, p)) {
    if (!keep(oc.name)) continue;
    std::vector<float> v(n, 1.f);
    if (oc.src)
      for (size_t i = 0; i < n; ++i) v[i] = oc.src[i * oc.stride];
    out.push_back(std::move(v));
  }
  return out;
}

// The judged layer's channels (alpha left out).
std::vector<std::vector<float>> layer_planes(const FrameResult& fr, const Params& p,
                                             const std::string& layer) {
  return planes(fr, p, [&](const std::string& name) {
    return name.rfind(layer + ".", 0) == 0 && name != layer + ".A";
  });
}

std::vector<float> history_plane(const FrameResult& fr, const Params& p) {
  auto h = planes(fr, p, [](const std::string& name) { return name == "history.Y"; });
  return h.empty() ? std::vector<float>{} : std::move(h.front());
}

// dir/frame_<numbers[k]>.exr linked to sources[k], with the source's camera sidecar.
SequencePlan linked(const fs::path& dir, const std::vector<std::string>& sources,
                    const std::vector<int>& numbers) {
  fs::create_directories(dir);
  const io::FramePattern pattern((dir / "frame_####.exr").string());
  for (size_t k = 0; k < sources.size(); ++k) {
    const fs::path to = pattern.path(numbers[k]);
    fs::create_symlink(fs::absolute(sources[k]), to);
    const std::string side = io::sidecar_path_for(sources[k]);
    if (fs::exists(side)) fs::create_symlink(fs::absolute(side), io::sidecar_path_for(to));
  }
  SequencePlan plan{pattern, numbers, {}, {}};
  return plan;
}

// Runs `p` over `plan`, calling `f` for every delivered frame; `cut` is told of cuts.
void each_frame(const SequencePlan& plan, const Params& p,
                const std::function<void(const FrameResult&, const Params&)>& f,
                bool* cut = nullptr) {
  const SequenceJob job(plan, p);
  SequenceJob::Hooks hooks;
  hooks.deliver = [&](FrameResult& fr) { f(fr, job.params()); };
  hooks.cut = [&](int, const TemporalReport&) {
    if (cut) *cut = true;
  };
  job.run(hooks, Overlap::off);
}

void rmse_in(const FrameResult& fr, const Params& p, const BenchReference& ref,
             const io::MaskSpec& mask, const std::vector<unsigned char>& region, ErrorStats& acc) {
  acc.add(compare_with_reference(fr, p, ref, mask, &region).overall);
}

// Thin objects: geometry pixels with, within kThinPixels along a row (or a column), a pixel
// on each side whose depth is kThinRise farther (or background).
std::vector<unsigned char> thin_mask(const std::vector<float>& z, int w, int h, double bg) {
  std::vector<unsigned char> m(z.size(), 0);
  auto farther = [&](int x, int y, float zc) {
    const float v = z[size_t(y) * w + x];
    return !(v < bg) || v > zc * float(1 + kThinRise);
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float zc = z[size_t(y) * w + x];
      if (!(zc < bg)) continue;
      bool l = false, r = false, u = false, d = false;
      for (int k = 1; k <= kThinPixels; ++k) {
        l |= x - k >= 0 && farther(x - k, y, zc);
        r |= x + k < w && farther(x + k, y, zc);
        u |= y - k >= 0 && farther(x, y - k, zc);
        d |= y + k < h && farther(x, y + k, zc);
      }
      m[size_t(y) * w + x] = (l && r) || (u && d);
    }
  return m;
}

// A copy of `src` (all channels as float) with `edit` applied to its pixels, beside the
// source's sidecar.
std::string edited_copy(
    const std::string& src, const fs::path& dir, int frame,
    const std::function<void(const OIIO::ImageSpec&, std::vector<float>&)>& edit) {
  fs::create_directories(dir);
  OIIO::ImageBuf in(src);
  if (!in.read(0, 0, true, OIIO::TypeDesc::FLOAT))
    throw Error(Exit::input, src + ": cannot read: " + in.geterror());
  OIIO::ImageSpec spec = in.spec();
  std::vector<float> px(size_t(spec.width) * spec.height * spec.nchannels);
  in.get_pixels(in.roi(), OIIO::TypeDesc::FLOAT, px.data());
  edit(spec, px);
  spec.set_format(OIIO::TypeDesc::FLOAT);
  spec.channelformats.clear();
  OIIO::ImageBuf out(spec);
  out.set_pixels(out.roi(), OIIO::TypeDesc::FLOAT, px.data());
  const std::string path = io::FramePattern((dir / "frame_####.exr").string()).path(frame);
  if (!out.write(path)) throw Error(Exit::output, path + ": cannot write: " + out.geterror());
  const std::string side = io::sidecar_path_for(src);
  if (fs::exists(side)) fs::create_symlink(fs::absolute(side), io::sidecar_path_for(path));
  return path;
}

}  // namespace

StabilityFigures measure_stability(const BenchSettings& s, const BenchConfig& c,
                                   const BenchReference& ref, const std::string& scratch_dir) {
  StabilityFigures out;
  out.layer = ref.layer;
  const fs::path scratch(scratch_dir);
  const SequencePlan plan = plan_sequence(s.shot, s.frames, 0, "");
  Params p = c.params;
  p.outputs = {ref.layer, "history"};
  // "auto" resolved on the shot once: the linked sequences below start elsewhere.
  p = SequenceJob(plan, p).params();
  const int f0 = plan.frames.front();
  const std::string first_path = plan.input.path(f0);

  // The shot itself: revealed pixels, the edge band, thin objects; the first frames kept for
  // the cut.
  ErrorStats revealed, other, edge, interior, thin, rest;
  size_t n_revealed = 0, n_geometry = 0;
  std::vector<std::vector<std::vector<float>>> kept;  // frames 1..kCutFrames
  each_frame(plan, p, [&](const FrameResult& fr, const Params& q) {
    const int w = fr.outputs.width, h = fr.outputs.height;
    const size_t n = size_t(w) * h;
    if (int(kept.size()) < kCutFrames) kept.push_back(layer_planes(fr, q, ref.layer));
    if (fr.index > 1) {
      const std::vector<float> hist = history_plane(fr, q);
      std::vector<unsigned char> r(n), o(n);
      for (size_t i = 0; i < n; ++i) {
        r[i] = hist[i] == 1.f;
        o[i] = hist[i] > 1.f;
        n_revealed += r[i];
        n_geometry += hist[i] > 0.f;
      }
      rmse_in(fr, q, ref, s.mask, r, revealed);
      rmse_in(fr, q, ref, s.mask, o, other);
    }
    const int band = std::max(1, int(std::lround(kEdgeBand * std::min(w, h))));
    std::vector<unsigned char> e(n), in(n);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const bool at_edge = std::min({x, y, w - 1 - x, h - 1 - y}) < band;
        e[size_t(y) * w + x] = at_edge;
        in[size_t(y) * w + x] = !at_edge;
      }
    rmse_in(fr, q, ref, s.mask, e, edge);
    rmse_in(fr, q, ref, s.mask, in, interior);
    if (fr.input->has("depth")) {
      const GBuffer g = io::read_fields(*fr.input, {"depth"}, q);
      std::vector<unsigned char> t = thin_mask(g.depth, w, h, q.background_depth), nt(n);
      for (size_t i = 0; i < n; ++i) nt[i] = !t[i] && g.depth[i] < q.background_depth;
      rmse_in(fr, q, ref, s.mask, t, thin);
      rmse_in(fr, q, ref, s.mask, nt, rest);
    }
  });
  auto rmse_or = [](const ErrorStats& e) { return e.count ? e.rmse() : -1.0; };
  out.revealed_rmse = rmse_or(revealed);
  out.other_rmse = rmse_or(other);
  out.revealed_share = n_geometry ? double(n_revealed) / double(n_geometry) : -1;
  out.edge_rmse = rmse_or(edge);
  out.interior_rmse = rmse_or(interior);
  out.thin_rmse = rmse_or(thin);
  out.rest_rmse = rmse_or(rest);
  out.thin_share =
      thin.count + rest.count ? double(thin.count) / double(thin.count + rest.count) : -1;

  // A static camera: the first frame repeated, numbered on from it.
  {
    std::vector<std::string> src(kStaticFrames, first_path);
    std::vector<int> numbers;
    for (int k = 0; k < kStaticFrames; ++k) numbers.push_back(f0 + k);
    std::vector<std::vector<float>> prev;
    double sum = 0;
    int terms = 0;
    each_frame(linked(scratch / "static", src, numbers), p,
               [&](const FrameResult& fr, const Params& q) {
                 std::vector<std::vector<float>> cur = layer_planes(fr, q, ref.layer);
                 const std::vector<float> hist = history_plane(fr, q);
                 if (!prev.empty()) {
                   double d = 0, m = 0;
                   for (size_t ch = 0; ch < cur.size(); ++ch)
                     for (size_t i = 0; i < cur[ch].size(); ++i)
                       if (hist[i] > 0.f) {
                         d += std::fabs(double(cur[ch][i]) - prev[ch][i]);
                         m += std::fabs(double(cur[ch][i]));
                       }
                   if (m > 0) sum += d / m, ++terms;
                 }
                 prev = std::move(cur);
               });
    out.flicker = terms ? sum / terms : -1;
  }

  // A cut: the shot's last frame on disk, then its first frames with their own numbers.
  const std::vector<int> on_disk = plan.input.existing_frames();
  if (plan.frames.size() > 1 && f0 > 0 && !on_disk.empty() && on_disk.back() != f0) {
    const int m = std::min<int>(kCutFrames, int(plan.frames.size()));
    std::vector<std::string> src = {plan.input.path(on_disk.back())};
    std::vector<int> numbers = {f0 - 1};
    for (int k = 0; k < m; ++k) {
      src.push_back(plan.input.path(plan.frames[size_t(k)]));
      numbers.push_back(plan.frames[size_t(k)]);
    }
    SequencePlan cut_plan = linked(scratch / "cut", src, numbers);
    std::vector<double> diff;
    each_frame(
        cut_plan, p,
        [&](const FrameResult& fr, const Params& q) {
          if (fr.index == 1) return;  // the frame before the cut
          const auto cur = layer_planes(fr, q, ref.layer);
          const auto& whole = kept[fr.index - 2];
          double d = 0, b = 0;
          for (size_t ch = 0; ch < cur.size(); ++ch)
            for (size_t i = 0; i < cur[ch].size(); ++i) {
              const double e = double(cur[ch][i]) - whole[ch][i];
              d += e * e;
              b += double(whole[ch][i]) * whole[ch][i];
            }
          diff.push_back(b > 0 ? std::sqrt(d / b) : 0);
        },
        &out.cut_detected);
    // The first frame from which every later one matches the uncut run.
    int k = int(diff.size());
    while (k > 0 && diff[size_t(k - 1)] < kRecovered) --k;
    out.cut_recovery_frames = k < int(diff.size()) ? k : -1;
  }

  // Robustness: zero normals must give finite outputs; non-finite input must be refused.
  const io::InputFrame first = io::open_frame(first_path, f0, p);
  const Params& all = c.params;  // the configuration's own outputs
  if (first.has("normal")) {
    const std::vector<int> nc = first.channels.at("normal");
    const std::string path = edited_copy(first_path, scratch / "zero_normals", f0,
                                         [&](const OIIO::ImageSpec& sp, std::vector<float>& px) {
                                           const size_t n = size_t(sp.width) * sp.height;
                                           for (size_t i = 0; i < n; i += 100)
                                             for (int ch : nc)
                                               px[i * sp.nchannels + size_t(ch)] = 0.f;
                                         });
    bool finite = true;
    each_frame(plan_sequence(path, "", 0, ""), all, [&](const FrameResult& fr, const Params& q) {
      for (const io::OutputChannel& oc : io::output_plan(fr.outputs, q)) {
        if (!oc.src) continue;
        const size_t n = size_t(fr.outputs.width) * fr.outputs.height;
        for (size_t i = 0; i < n; ++i) finite &= std::isfinite(oc.src[i * oc.stride]);
      }
    });
    out.zero_normals_finite = finite;
  }
  out.robust = out.zero_normals_finite;
  struct Injection {
    std::string name, field;
    float value;
  };
  const std::vector<Injection> injections = {{"NaN depth", "depth", std::nanf("")},
                                             {"infinite depth", "depth", INFINITY},
                                             {"NaN DiffCol", "diffcol", std::nanf("")}};
  for (const Injection& inj : injections) {
    if (!first.has(inj.field)) continue;
    const int ch = first.channels.at(inj.field)[0];
    const std::string path = edited_copy(
        first_path, scratch / ("inject_" + inj.field + std::to_string(&inj - injections.data())),
        f0, [&](const OIIO::ImageSpec& sp, std::vector<float>& px) {
          px[(size_t(sp.height / 2) * sp.width + sp.width / 2) * sp.nchannels + size_t(ch)] =
              inj.value;
        });
    std::string what;
    try {
      each_frame(plan_sequence(path, "", 0, ""), all, [](const FrameResult&, const Params&) {});
      what = "accepted";
      out.robust = false;
    } catch (const Error& e) {
      what = e.code() == Exit::bad_data ? "refused (exit 5)"
                                        : "refused (exit " + std::to_string(int(e.code())) + ")";
      if (e.code() != Exit::bad_data) out.robust = false;
    }
    out.bad_input += (out.bad_input.empty() ? "" : ", ") + inj.name + ": " + what;
  }
  return out;
}

}  // namespace hbil::pipeline
