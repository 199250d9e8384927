// temporal.cpp: see temporal.h.
#include "hbil/temporal.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "hbil/error.h"
#include "hbil/pushpull.h"
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

}  // namespace

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

TemporalChain::TemporalChain(Params p) : p_(std::move(p)) {}

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
  const size_t n_px = v.pixels();
  size_t geometry = 0;
  for (size_t i = 0; i < n_px; ++i) geometry += !v.is_background(i);

  // Cut detection before anything is reprojected.
  rep.first = !has_history_;
  if (has_history_ && (view_.width != v.width || view_.height != v.height))
    cut = true, rep.cut_reason = "resolution changed";
  if (cut && rep.cut_reason.empty()) rep.cut_reason = "given";
  if (has_history_ && !cut) {
    rep.cut_reason = camera_cut(cam_, cam, median_depth(v), p_);
    cut = !rep.cut_reason.empty();
  }

  // Reprojection of the history into this frame.
  Reprojected r;
  bool history = has_history_ && !cut;
  if (history) {
    const ReprojectTolerance tol{float(p_.history_depth_tolerance), float(p_.history_normal_cos)};
    // Blender's Vector points at frame N−1: "auto" scatters when the history is another frame.
    const bool vector = p_.reprojection == "vector" ||
                        (p_.reprojection == "auto" && !g.motion.empty() && frame == frame_ + 1);
    rep.reprojection = vector ? "vector" : "scatter";
    r = vector ? reproject_gather(view_, cam_, data_, kChannels, v, cam, g.motion, tol)
               : reproject_scatter(view_, cam_, data_, kChannels, v, cam, tol);
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

  // Feedback: the history's irradiance, with its holes filled by push/pull.
  const bool gather = gathers(p_);
  FrameInputs in;
  in.rotate = true;
  in.frame = frame;
  std::vector<Vec3>& feedback = in.feedback;
  if (history && gather && p_.feedback) {
    std::vector<float> e(3 * n_px), depth(n_px);
    for (size_t i = 0; i < n_px; ++i) {
      for (int c = 0; c < 3; ++c) e[3 * i + c] = r.value[kChannels * i + c];
      depth[i] = v.is_background(i) ? float(kBackgroundLimit) * 10 : v.position[i].z;
    }
    std::vector<uint8_t> filled;
    if (p_.push_pull)
      e = push_pull(v.width, v.height, 3, e, r.valid, depth, float(p_.history_depth_tolerance),
                    &filled);
    size_t n_filled = 0;
    for (size_t i = 0; i < n_px; ++i) n_filled += !filled.empty() && filled[i];
    rep.filled = geometry ? double(n_filled) / double(geometry) : 0;
    feedback.resize(n_px);
    for (size_t i = 0; i < n_px; ++i) feedback[i] = Vec3{e[3 * i], e[3 * i + 1], e[3 * i + 2]};
  }

  // The colour fields as floats from here on: the history and the feedback's temporaries
  // are no longer in memory.
  if (release) release->unpack();
  HorizonImage h = search_frame(v, g, cam, p_, std::move(in));
  std::vector<float>().swap(v.thickness);  // only the search reads it

  // Accumulation with the history; the result becomes the next frame's history. It is
  // written over the reprojected history in place (each pixel reads its history before it
  // writes; background and rejected pixels hold 0 there, as a fresh buffer would).
  std::vector<float> next =
      history ? std::move(r.value) : std::vector<float>(kChannels * n_px, 0.f);
  const bool has_e = !h.irradiance.empty();
  tbb::parallel_for(0, v.height, [&](int y) {
    for (int x = 0; x < v.width; ++x) {
      const size_t i = size_t(y) * v.width + x;
      if (v.is_background(i)) continue;
      float n = 1;
      if (history && r.valid[i]) {
        const float* hv = &next[kChannels * i];
        n = std::min(hv[8] + 1.f, float(p_.history_max));
        const float a = std::max(1.f / n, 1.f - float(p_.history_weight));
        auto mix = [a](float old, float cur) { return old + a * (cur - old); };
        if (has_e) {
          Vec3& e = h.irradiance[i];
          e = Vec3{mix(hv[0], e.x), mix(hv[1], e.y), mix(hv[2], e.z)};
        }
        h.ao[i] = mix(hv[3], h.ao[i]);
        h.vis[i] = mix(hv[4], h.vis[i]);
        const Vec3 b_old = Vec3(cam.world_dir_to_view(Vec3d(Vec3{hv[5], hv[6], hv[7]})));
        h.bent[i] =
            Vec3{mix(b_old.x, h.bent[i].x), mix(b_old.y, h.bent[i].y), mix(b_old.z, h.bent[i].z)};
      }
      float* o = &next[kChannels * i];
      if (has_e) o[0] = h.irradiance[i].x, o[1] = h.irradiance[i].y, o[2] = h.irradiance[i].z;
      o[3] = h.ao[i];
      o[4] = h.vis[i];
      const Vec3 bw = Vec3(cam.view_dir_to_world(Vec3d(h.bent[i])));
      o[5] = bw.x, o[6] = bw.y, o[7] = bw.z;
      o[8] = n;
    }
  });
  AoFrame out = assemble_frame(v, g, cam, p_, std::move(h), environment, release);
  if (p_.wants("history")) {
    out.history.resize(n_px);
    for (size_t i = 0; i < n_px; ++i) out.history[i] = next[kChannels * i + 8];
  }
  view_ = std::move(v);
  cam_ = cam;
  frame_ = frame;
  data_ = std::move(next);
  has_history_ = true;
  if (report) *report = rep;
  return out;
}

}  // namespace hbil
