// temporal.cpp: see temporal.h.
#include "hbil/temporal.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "hbil/error.h"
#include "hbil/pushpull.h"
#include "hbil/reduced.h"
#include "hbil/reproject.h"

namespace hbil {

namespace {

constexpr double kBackgroundLimit = 1e30;

double median_depth(const ViewGBuffer& v) {
  std::vector<float> z;
  z.reserve(v.pixels());
  for (size_t i = 0; i < v.pixels(); ++i)
    if (!v.is_background(i)) z.push_back(v.position[i].z);
  if (z.empty()) return 0;
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  return z[z.size() / 2];
}

// Angle of the rotation between two world-to-view rotations, degrees.
double turn_degrees(const Mat3d& a, const Mat3d& b) {
  const Mat3d r = a.transposed() * b;
  const double c = std::clamp((r.m[0][0] + r.m[1][1] + r.m[2][2] - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180 / std::numbers::pi;
}

// history_window W: chain c (0 or 1) restarts at the frames F with (F + cW) mod 2W = 0; at
// age a = (F + cW) mod 2W it has a + 1 frames and weighs a² (2W − 1 − a) in the blend: 0 at
// its first frame and at its last, so that its restart never shows, and more as it holds
// more frames (for independent frames, an effective count of 6.5 frames at W = 5, where
// a (2W − 1 − a) gives 5.6, and smaller changes from frame to frame). The other chain is then W
// frames old, so the weights never both vanish (W >= 2).
int window_age(int frame, int chain, int w) {
  const int m = 2 * w, f = frame + chain * w;
  return (f % m + m) % m;
}
int window_epoch(int frame, int chain, int w) {
  const int m = 2 * w, f = frame + chain * w;
  return f >= 0 ? f / m : -((m - 1 - f) / m);
}
float window_weight(int frame, int chain, int w) {
  const int a = window_age(frame, chain, w);
  return float(a) * float(a) * float(2 * w - 1 - a);
}

}  // namespace

int window_memory(int window, int frame) {
  if (window <= 0) return 0;
  int memory = 0;
  for (int k = 0; k < 2; ++k)
    if (window_weight(frame, k, window) > 0)
      memory = std::max(memory, window_age(frame, k, window));
  return memory;
}

std::string camera_cut(const Camera& prev, const Camera& cur, double depth, const Params& p) {
  const double move = length(cur.centre() - prev.centre());
  const double turn = turn_degrees(prev.R, cur.R);
  std::ostringstream s;
  s.precision(3);
  if (depth > 0 && move > p.cut_camera_jump * depth)
    s << "camera moved " << move << " (median depth " << depth << ")";
  else if (turn > p.cut_camera_angle)
    s << "camera turned " << turn << " degrees";
  return s.str();
}

TemporalChain::TemporalChain(Params p)
    : p_(std::move(p)), cache_(p_.radiance_cache, p_.radiance_cache_ahead) {}

void TemporalChain::look_ahead(const GBuffer& g, const Camera& cam, int frame, bool cut,
                               const Camera* before) {
  if (p_.radiance_cache_ahead <= 0) return;
  // The entries take positions alone: no thickness estimated from the extent.
  Params q = p_;
  q.thickness_extent = false;
  const ViewGBuffer v = make_view_gbuffer(g, cam, q);
  if (!cut && before) cut = !camera_cut(*before, cam, median_depth(v), p_).empty();
  cache_.add_ahead(v, cam, g, frame, cut);
}

AoFrame TemporalChain::process(const GBuffer& g, const Camera& cam, int frame, bool cut,
                               const SH9* environment, TemporalReport* report) {
  return run(g, nullptr, cam, frame, cut, environment, report);
}

AoFrame TemporalChain::process(GBuffer&& g, const Camera& cam, int frame, bool cut,
                               const SH9* environment, TemporalReport* report) {
  return run(g, &g, cam, frame, cut, environment, report);
}

AoFrame TemporalChain::run(const GBuffer& g, GBuffer* release, const Camera& cam, int frame,
                           bool cut, const SH9* environment, TemporalReport* report) {
  if (!g.packed.empty() && !release)
    throw Error(Exit::failure, "TemporalChain::process: a packed G-buffer (unpack it first)");
  TemporalReport rep;
  if (p_.wants("auto")) p_ = resolve_frame_outputs(g, p_);  // once, on the first frame
  ViewGBuffer v = make_view_gbuffer(g, cam, p_);
  if (release) {  // the geometry is in v now
    std::vector<float>().swap(release->depth);
    std::vector<float>().swap(release->backdepth);
    std::vector<Vec3>().swap(release->position);
    // The world normal is what background pixels output as their bent normal (assemble_frame):
    // released when that is zero everywhere (it is for Blender), kept otherwise.
    bool zero = true;
    for (size_t i = 0; zero && i < release->normal.size(); ++i)
      zero = !v.is_background(i) ||
             (release->normal[i].x == 0 && release->normal[i].y == 0 && release->normal[i].z == 0);
    if (zero) std::vector<Vec3>().swap(release->normal);
  }
  // With a reduced search (search_scale f > 1) the chain works on the searched texels
  // (reduce_view): it reprojects, fills, and blends them with their history, and the blend is
  // upsampled to the frame's pixels once, at the end. `cv` is the grid it works on.
  const int f = effective_search_scale(p_, v.width, v.height);
  const float depth_tol = float(p_.depth_tolerance);
  ViewGBuffer lo = f > 1 ? reduce_view(v, f) : ViewGBuffer{};
  const ViewGBuffer& cv = f > 1 ? lo : v;
  UpsamplePlan plan;
  if (f > 1) plan = plan_upsample(v, lo, f, depth_tol);
  const size_t n_px = cv.pixels();
  size_t geometry = 0;
  for (size_t i = 0; i < n_px; ++i) geometry += !cv.is_background(i);

  // Cut detection before anything is reprojected.
  rep.first = !has_history_;
  if (has_history_ && (width_ != v.width || height_ != v.height))
    cut = true, rep.cut_reason = "resolution changed";
  if (cut && rep.cut_reason.empty()) rep.cut_reason = "given";
  if (has_history_ && !cut) {
    rep.cut_reason = camera_cut(cam_, cam, median_depth(v), p_);
    cut = !rep.cut_reason.empty();
  }

  // Reprojection of the history into this frame.
  // With history_window, two chains of per_chain channels each (window_weight), then the
  // frame's own irradiance before accumulation, which is what is fed back (when gathering).
  const int window = p_.history_window, chains = window > 0 ? 2 : 1;
  const bool gather = gathers(p_);
  const int ne = gather ? kIrradianceChannels : 0;  // a chain's irradiance channels, first
  const int per_chain = ne + kOcclusionChannels;
  const int channels = per_chain * chains + (window > 0 ? ne : 0);
  Reprojected r;
  bool history = has_history_ && !cut;
  if (history) {
    const ReprojectTolerance tol{float(p_.history_depth_tolerance), float(p_.history_normal_cos)};
    // Blender's Vector points at frame N−1: "auto" scatters when the history is another frame.
    const bool vector = p_.reprojection == "vector" ||
                        (p_.reprojection == "auto" && !g.motion.empty() && frame == frame_ + 1);
    rep.reprojection = vector ? "vector" : "scatter";
    if (vector && f > 1) {
      r = reproject_gather(view_, cam_, data_, channels, cv, cam, reduce_motion(v, lo, f, g.motion),
                           tol);
    } else {
      r = vector ? reproject_gather(view_, cam_, data_, channels, cv, cam, g.motion, tol)
                 : reproject_scatter(view_, cam_, data_, channels, cv, cam, tol);
    }
    size_t accepted = 0;
    for (size_t i = 0; i < n_px; ++i) accepted += r.valid[i] != 0;
    rep.history = geometry ? double(accepted) / double(geometry) : 0;
    if (geometry && 1 - rep.history > p_.cut_rejected) {
      std::ostringstream s;
      s << "history rejected on " << std::lround(100 * (1 - rep.history)) << " % of pixels";
      rep.cut_reason = s.str();
      cut = true;
      history = false;
      rep.history = 0;
    }
  }
  if (release) std::vector<float>().swap(release->motion);  // only the reprojection reads it
  rep.cut = cut && !rep.first;
  if (rep.first) rep.cut_reason.clear();
  // The previous frame's history and view were only needed for the reprojection: released
  // now, so that they do not take memory through the search (they are replaced at the end).
  std::vector<float>().swap(data_);
  view_ = ViewGBuffer{};
  if (!history) r = Reprojected{};
  // The radiance cache holds the frames since the last cut (a cut may be another set).
  const bool cache = (p_.radiance_cache > 0 || p_.radiance_cache_ahead > 0) && gather;
  if (cut || rep.first) cache_.clear();
  const bool reads_cache = (cache || !p_.panorama.empty()) && gather;

  // Feedback: the history's irradiance, with its holes filled by push/pull.
  FrameInputs in;
  in.rotate = true;
  in.frame = frame;
  if (reads_cache) in.cache = &cache_;
  in.tiles = tiles_;
  if (f > 1) {
    in.keep_reduced = true;
    in.reduced = &lo;
    in.plan = &plan;
  }
  std::vector<Vec3>& feedback = in.feedback;
  if (history && gather && p_.feedback) {
    std::vector<float> e(3 * n_px), depth(n_px);
    // The history's accumulated irradiance; with history_window its frame's own, so that
    // what is fed back forgets a cut-off past by a bounce per frame, not through the means.
    const size_t e_at = window > 0 ? size_t(per_chain) * chains : 0;
    for (size_t i = 0; i < n_px; ++i) {
      for (int c = 0; c < 3; ++c) e[3 * i + c] = r.value[size_t(channels) * i + e_at + c];
      depth[i] = cv.is_background(i) ? float(kBackgroundLimit) * 10 : cv.position[i].z;
    }
    std::vector<uint8_t> filled;
    if (p_.push_pull)
      e = push_pull(cv.width, cv.height, 3, e, r.valid, depth, float(p_.history_depth_tolerance),
                    &filled);
    size_t n_filled = 0;
    for (size_t i = 0; i < n_px; ++i) n_filled += !filled.empty() && filled[i];
    rep.filled = geometry ? double(n_filled) / double(geometry) : 0;
    feedback.resize(n_px);
    for (size_t i = 0; i < n_px; ++i) feedback[i] = Vec3{e[3 * i], e[3 * i + 1], e[3 * i + 2]};
    if (f > 1) {  // to the pixels, whose DiffCol makes the source radiance
      HorizonImage fb;
      fb.width = cv.width;
      fb.height = cv.height;
      fb.irradiance = std::move(feedback);
      feedback = std::move(upsample_horizon(v, lo, plan, fb).irradiance);
      // The texels hold the light that reaches them; each pixel reflects its own share of it.
      weigh_diffuse(g, feedback);
    }
  }

  // The colour fields as floats from here on: the history and the feedback's temporaries
  // are no longer in memory.
  if (release) release->unpack();
  // slices "auto": a frame without history (the chain's first, or the first after a cut) is
  // searched as a single frame is, with 2 slices: nothing accumulated makes up for one yet.
  HorizonImage h = history ? search_frame(v, g, cam, p_, std::move(in))
                           : search_frame(v, g, cam, resolve_auto_slices(p_, false), std::move(in));
  std::vector<float>().swap(v.thickness);  // only the search reads it
  std::vector<float>().swap(lo.thickness);

  // Accumulation with the history; the result becomes the next frame's history. It is
  // written over the reprojected history in place (each pixel reads its history before it
  // writes; background and rejected pixels hold 0 there, as a fresh buffer would).
  std::vector<float> next =
      history ? std::move(r.value) : std::vector<float>(size_t(channels) * n_px, 0.f);
  const bool has_e = !h.irradiance.empty();
  // Each chain's weight in this frame's output, and whether it restarts here.
  float wt[2] = {1.f, 0.f};
  bool restart[2] = {false, false};
  for (int k = 0; window > 0 && k < 2; ++k) {
    wt[k] = window_weight(frame, k, window);
    restart[k] = history && window_epoch(frame, k, window) != window_epoch(frame_, k, window);
  }
  const float wt_sum = wt[0] + wt[1];
  std::vector<float> n_out(p_.wants("history") ? n_px : 0);
  tbb::parallel_for(0, cv.height, [&](int y) {
    for (int x = 0; x < cv.width; ++x) {
      const size_t i = size_t(y) * cv.width + x;
      if (cv.is_background(i)) continue;
      // This frame's values; each chain blends them with its history, and the output is
      // the chain's (or the chains' blend).
      const Vec3 e_cur = has_e ? h.irradiance[i] : Vec3{};
      const float ao_cur = h.ao[i], vis_cur = h.vis[i];
      const Vec3 b_cur = h.bent[i];
      if (window > 0 && ne > 0) {
        float* o = &next[size_t(channels) * i + size_t(per_chain) * chains];
        o[0] = e_cur.x, o[1] = e_cur.y, o[2] = e_cur.z;
      }
      Vec3 e_sum, b_sum;
      float ao_sum = 0, vis_sum = 0, n_sum = 0;
      for (int k = 0; k < chains; ++k) {
        float* e_ch = &next[size_t(channels) * i + size_t(per_chain) * k];
        float* o = e_ch + ne;  // ao, vis, bent (3), n
        Vec3 e = e_cur, b = b_cur;
        float ao = ao_cur, vis = vis_cur, n = 1;
        if (history && r.valid[i] && !restart[k]) {
          const float* hv = o;
          float a;
          if (window > 0) {
            n = hv[5] + 1.f;
            a = 1.f / n;
          } else {
            n = std::min(hv[5] + 1.f, float(p_.history_max));
            a = std::max(1.f / n, 1.f - float(p_.history_weight));
          }
          auto mix = [a](float old, float cur) { return old + a * (cur - old); };
          if (has_e && ne > 0) e = Vec3{mix(e_ch[0], e.x), mix(e_ch[1], e.y), mix(e_ch[2], e.z)};
          ao = mix(hv[0], ao);
          vis = mix(hv[1], vis);
          const Vec3 b_old = Vec3(cam.world_dir_to_view(Vec3d(Vec3{hv[2], hv[3], hv[4]})));
          b = Vec3{mix(b_old.x, b.x), mix(b_old.y, b.y), mix(b_old.z, b.z)};
        }
        if (has_e && ne > 0) e_ch[0] = e.x, e_ch[1] = e.y, e_ch[2] = e.z;
        o[0] = ao;
        o[1] = vis;
        const Vec3 bw = Vec3(cam.view_dir_to_world(Vec3d(b)));
        o[2] = bw.x, o[3] = bw.y, o[4] = bw.z;
        o[5] = n;
        if (chains == 1) {
          e_sum = e, b_sum = b, ao_sum = ao, vis_sum = vis, n_sum = n;
        } else {
          e_sum += e * wt[k], b_sum += b * wt[k];
          ao_sum += ao * wt[k], vis_sum += vis * wt[k], n_sum += n * wt[k];
        }
      }
      if (chains > 1) {
        const float inv = 1.f / wt_sum;
        e_sum = e_sum * inv, b_sum = b_sum * inv;
        ao_sum *= inv, vis_sum *= inv, n_sum *= inv;
      }
      if (has_e) h.irradiance[i] = e_sum;
      h.ao[i] = ao_sum;
      h.vis[i] = vis_sum;
      h.bent[i] = b_sum;
      if (!n_out.empty()) n_out[i] = n_sum;
    }
  });
  if (f > 1) {  // the blend, to the pixels
    h = upsample_horizon(v, lo, plan, h);
    if (has_e) weigh_diffuse(g, h.irradiance);
    if (!n_out.empty()) n_out = upsample_count(v, lo, plan, n_out);
  }
  if (cache && has_e) cache_.add(v, cam, g, h.irradiance, frame);
  AoFrame out = assemble_frame(v, g, cam, p_, std::move(h), environment, release);
  if (p_.wants("history")) out.history = std::move(n_out);
  width_ = v.width;
  height_ = v.height;
  view_ = f > 1 ? std::move(lo) : std::move(v);
  cam_ = cam;
  frame_ = frame;
  data_ = std::move(next);
  has_history_ = true;
  if (report) *report = rep;
  return out;
}

}  // namespace hbil
