// sequence_job.cpp: see sequence_job.h.
#include "pipeline/sequence_job.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <map>
#include <optional>
#include <sstream>

#include "hbil/error.h"
#include "hbil/radiance_cache.h"
#include "hbil/scene_scale.h"
#include "io/environment.h"
#include "io/exr_frame.h"
#include "io/sequence.h"

namespace hbil::pipeline {

GBuffer read_panorama(const std::string& path, int frame, const Params& p) {
  const io::InputFrame in = io::open_frame(path, frame, p);
  std::vector<std::string> fields = {"position", "depth", "diffcol", "diffdir"};
  io::require_fields(in, fields, "panorama");
  if (in.has("emit")) fields.push_back("emit");
  return io::read_fields(in, fields, p);
}

namespace {

using Clock = std::chrono::steady_clock;

double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// A frame whose data window (size or origin) is not that of the run's first frame
// (first_path): exit 5.
void require_same_size(const io::InputFrame& in, const OIIO::ImageSpec& first,
                       const std::string& first_path) {
  if (in.spec.width != first.width || in.spec.height != first.height)
    throw Error(Exit::bad_data, in.where() + ": resolution " + std::to_string(in.spec.width) + "x" +
                                    std::to_string(in.spec.height) + " differs from " +
                                    std::to_string(first.width) + "x" +
                                    std::to_string(first.height) + " of " + first_path);
  // The history is carried over in the data window's raster.
  if (in.spec.x != first.x || in.spec.y != first.y)
    throw Error(Exit::bad_data, in.where() + ": data window at (" + std::to_string(in.spec.x) +
                                    ", " + std::to_string(in.spec.y) + ") differs from (" +
                                    std::to_string(first.x) + ", " + std::to_string(first.y) +
                                    ") of " + first_path);
}

}  // namespace

std::set<int> parse_cut_frames(const std::string& text) {
  const std::vector<int> frames = io::parse_frame_list(text, "--cut-frames");
  return {frames.begin(), frames.end()};
}

SequencePlan plan_sequence(const std::string& input, const std::string& frames, int preroll,
                           const std::string& cut_frames) {
  SequencePlan plan{io::FramePattern(input), {}, {}, {}};
  if (!plan.input.is_sequence()) {
    if (!frames.empty())
      throw Error(Exit::usage,
                  "--frames needs an input frame pattern, got the single file " + input);
    plan.frames = {io::frame_number_from_name(input).value_or(0)};
  } else if (!frames.empty()) {
    plan.frames = io::parse_frame_list(frames);
  } else {
    plan.frames = plan.input.existing_frames();
    if (plan.frames.empty())
      throw Error(Exit::input, input + ": no frames found matching the pattern");
  }
  if (preroll > 0) {
    if (!plan.input.is_sequence())
      throw Error(Exit::usage,
                  "--preroll needs an input frame pattern, got the single file " + input);
    const int first = plan.frames.front();
    for (int f : plan.input.existing_frames())
      if (f >= first - preroll && f < first) plan.preroll.push_back(f);
  }
  if (!cut_frames.empty()) plan.cuts = parse_cut_frames(cut_frames);
  return plan;
}

void configure_heap(int width, int height) {
  // glibc serves buffers above its heap threshold from mmap and returns them to the system
  // when they are freed; smaller ones stay in its heaps for reuse. The threshold is fixed here
  // (glibc's own moves up to 32 MiB as buffers are freed): at 32 MiB where a frame's RGB
  // float plane fits below it, with the heaps trimmed only above 64 MiB free (glibc's rule
  // there), so that frame buffers are reused without page faults; at 1 MiB where it does not
  // (3840x2160 and up: those planes are mapped and unmapped every frame anyway), so that the
  // smaller buffers are returned too and add nothing to the run's peak memory. 1 MiB until
  // the first frame's size is known.
  constexpr size_t kHeapMax = size_t(32) << 20;
  if (size_t(width) * size_t(height) * sizeof(Vec3) <= kHeapMax && width > 0) {
    mallopt(M_MMAP_THRESHOLD, int(kHeapMax));
    mallopt(M_TRIM_THRESHOLD, int(2 * kHeapMax));  // what glibc's own rule would reach
  } else {
    mallopt(M_MMAP_THRESHOLD, 1 << 20);
  }
}

Overlap parse_overlap(const std::string& text) {
  if (text == "on") return Overlap::on;
  if (text == "off") return Overlap::off;
  if (text == "auto") return Overlap::automatic;
  throw Error(Exit::usage, "--overlap " + text + ": expected on, off or auto");
}

SequenceJob::SequenceJob(SequencePlan plan, const Params& requested) : plan_(std::move(plan)) {
  const int f = plan_.frames.front();
  first_ = io::open_frame(plan_.input.path(f), f, requested);
  // Every input is there and has a readable header before anything is computed; then every
  // one has the passes the outputs need and the size of the first, so that what a header
  // can tell fails the run before its first frame is written.
  std::vector<io::InputFrame> others;
  for (const std::vector<int>* frames : {&plan_.preroll, &plan_.frames})
    for (int other : *frames)
      if (other != f) others.push_back(io::open_frame(plan_.input.path(other), other, requested));
  p_ = io::resolve_outputs(first_, requested, &why_dropped_);
  // The frames read ahead (the gather's radiance cache, with a chain, which a run of one frame
  // does not have): those after the plan are checked as its own are.
  if (p_.radiance_cache_ahead > 0 && gathers(p_) && chained() && plan_.input.is_sequence()) {
    const int begin = plan_.preroll.empty() ? plan_.frames.front() : plan_.preroll.front();
    const int end = plan_.frames.back() + p_.radiance_cache_ahead;
    for (int a : plan_.input.existing_frames()) {
      if (a <= begin || a > end) continue;
      ahead_.push_back(a);
      if (a > plan_.frames.back()) others.push_back(io::open_frame(plan_.input.path(a), a, p_));
    }
  }
  // slices "auto": the chain is decided on the whole plan, as run() decides it.
  p_ = resolve_auto_slices(p_, chained());
  const io::InputFrame& head = plan_.preroll.empty() ? first_ : others.front();
  auto check = [&](const io::InputFrame& in) {
    io::fields_needed(in, p_);  // exit 4, naming the channels looked for
    require_same_size(in, head.spec, head.path);
  };
  check(first_);
  for (const io::InputFrame& in : others) check(in);
  if (p_.gather_radius_auto || p_.thickness_auto || p_.gather_thickness_auto) {
    // From the depth (else position) and camera of the sequence's first frame on disk, not
    // the run's: every chunk of a shot (--frames, --preroll) then uses the values a run over
    // the whole shot uses. Read once more here, a field or two.
    int f0 = f;
    if (plan_.input.is_sequence()) {
      const std::vector<int> on_disk = plan_.input.existing_frames();
      if (!on_disk.empty()) f0 = on_disk.front();
    }
    const io::InputFrame shot_first =
        f0 == f ? first_ : io::open_frame(plan_.input.path(f0), f0, p_);
    io::fields_needed(shot_first, p_);  // a frame with neither depth nor position: exit 4
    GBuffer g = io::read_fields(shot_first, {shot_first.has("depth") ? "depth" : "position"}, p_);
    const Camera cam = io::find_camera(shot_first, g, p_);
    scene_ = measure_scene(g, cam, p_);
    p_ = resolve_scene_params(p_, scene_, &why_scene_);
  }
  // Far field: the environment projected to SH once for the whole run.
  if (!p_.environment.empty()) environment_ = io::load_environment(p_.environment);
  // calibration "auto": the renders in calibration/ beside the input, where there are any.
  p_.calibration = resolve_calibration(p_.calibration, plan_.input);
  // Only the gather has a fill to calibrate.
  if (!p_.calibration.empty() && gathers(p_)) {
    std::vector<int> all = plan_.preroll;
    all.insert(all.end(), plan_.frames.begin(), plan_.frames.end());
    calibration_ = Calibration(p_, plan_.input, all);
  }
  // unseen_carry "auto": with a calibration, whose render sets the fill's level.
  if (p_.unseen_carry_auto) {
    p_.unseen_carry = !calibration_.empty();
    p_.unseen_carry_auto = false;
  }
}

bool SequenceJob::overlaps(Overlap o) const {
  return o == Overlap::on ||
         (o == Overlap::automatic &&
          size_t(first_.spec.width) * size_t(first_.spec.height) <= (size_t(1) << 22));
}

void SequenceJob::run(const Hooks& hooks, Overlap overlap_mode, const SH9* given,
                      const std::set<int>& done) const {
  const SH9* environment = given ? given : environment_ ? &*environment_ : nullptr;
  // A frame as read: header, fields and camera, with the time each took.
  struct Loaded {
    io::InputFrame in;
    GBuffer g;
    Camera cam;
    ZeroNormals zero;
    GBuffer pano;  // Params::panorama's frame, or empty
    double read_ms = 0, camera_ms = 0;
  };
  auto load = [this](int frame) {
    const auto t0 = Clock::now();
    Loaded l;
    l.in = io::open_frame(plan_.input.path(frame), frame, p_);
    // Colour fields stored as half stay half until the frame's geometry is done with.
    l.g = io::read_fields(l.in, io::fields_needed(l.in, p_), p_, true);
    l.zero = find_zero_normals(l.g, p_);
    if (!p_.panorama.empty() && gathers(p_))  // only the gather reads it
      l.pano = read_panorama(io::FramePattern(p_.panorama).path(frame), frame, p_);
    const auto t_read = Clock::now();
    l.cam = io::find_camera(l.in, l.g, p_);
    l.read_ms = ms(t0, t_read);
    l.camera_ms = ms(t_read, Clock::now());
    return l;
  };
  // Pre-roll frames first (computed, not delivered), then the frames to deliver.
  std::vector<int> order = plan_.preroll;
  order.insert(order.end(), plan_.frames.begin(), plan_.frames.end());
  const bool temporal = chained();
  if (!done.empty()) {
    // Nothing after the last frame to deliver is needed; without a chain, no done frame is.
    const size_t npre = plan_.preroll.size();
    const auto to_deliver = [&](size_t k) { return k >= npre && !done.count(order[k]); };
    size_t end = order.size();
    while (end > npre && !to_deliver(end - 1)) --end;
    std::vector<int> kept;
    for (size_t k = 0; k < end && end > npre; ++k)
      if (temporal || k < npre || to_deliver(k)) kept.push_back(order[k]);
    order = kept;
  }
  if (order.empty()) return;  // every frame is done
  // The sequence's step: frames rendered on twos are no gap.
  const int step = sequence_step(order);
  std::optional<TemporalChain> chain;
  if (temporal) chain.emplace(p_);
  // The fill's level per frame (calibration.h): each calibration frame solved when a frame
  // first needs it, from that frame as read when it is the one, else read for it (the same
  // point either way).
  std::map<int, CalibrationPoint> solved;
  // A run of one frame (no pre-roll) never feeds a frame its history: its factor is solved
  // without the chain's feedback, as that frame is computed.
  // Each solve computes frames alone, without a chain: slices "auto" as for a run of one frame.
  Params solve_p = resolve_auto_slices(p_, false);
  if (plan_.frames.size() + plan_.preroll.size() == 1) solve_p.feedback = false;
  FillTiles tiles;  // the frame's calibrated fill level per surface (Params::calibration_tiles)
  auto calibrated_scale = [&](int frame, const GBuffer& g, const Camera& cam) {
    std::vector<CalibrationPoint> points;
    for (int c : calibration_.around(frame)) {
      auto it = solved.find(c);
      if (it == solved.end()) {
        const CalibrationPoint pt = c == frame ? calibration_.solve(solve_p, g, cam, c)
                                               : calibration_.solve(solve_p, plan_.input, c);
        if (hooks.calibrated) hooks.calibrated(pt);
        it = solved.emplace(c, pt).first;
      }
      points.push_back(it->second);
    }
    tiles = Calibration::tiles_at(points, frame);
    return Calibration::scale_at(points, frame);
  };
  Params single = p_;  // without a chain, with the frame's factor
  const bool overlap = overlaps(overlap_mode);
  // A delivered frame keeps its input header alive until its sink is done with it.
  struct Delivery {
    std::unique_ptr<io::InputFrame> input;
    FrameResult result;
  };
  auto deliver = [&hooks](Delivery d) {
    const auto t = Clock::now();
    if (hooks.deliver) hooks.deliver(d.result);
    d.result.times.deliver_ms = ms(t, Clock::now());
    d.result.outputs = AoFrame{};
    return d;
  };
  auto finish = [&hooks](std::future<Delivery>& f) {
    Delivery d = f.get();
    if (hooks.delivered) hooks.delivered(d.result);
  };
  // Params::radiance_cache_ahead: the frames of ahead_ up to radiance_cache_ahead after the
  // frame computed are added to the chain's cache before it (each read once more, its direct
  // light alone), in order; a gap in them is a cut as in the chain.
  size_t ahead_next = 0;
  std::optional<Camera> ahead_cam;
  int ahead_last = 0;
  auto look_ahead = [&](int frame, const Camera& cam) {
    if (!chain || ahead_.empty()) return;
    if (!ahead_cam) ahead_cam = cam, ahead_last = frame;
    for (; ahead_next < ahead_.size() && ahead_[ahead_next] <= frame + p_.radiance_cache_ahead;
         ++ahead_next) {
      const int a = ahead_[ahead_next];
      if (a <= ahead_last) continue;
      const io::InputFrame in = io::open_frame(plan_.input.path(a), a, p_);
      // Only what the cache's entries and the camera take: the geometry and the direct light.
      std::vector<std::string> fields;
      for (const std::string& field : io::fields_needed(in, p_))
        if (field == "depth" || field == "position" || field == "normal" || field == "alpha" ||
            field == "diffcol" || field == "diffdir" || field == "emit")
          fields.push_back(field);
      GBuffer g = io::read_fields(in, fields, p_);
      const Camera c = io::find_camera(in, g, p_);
      const bool cut = plan_.cuts.count(a) > 0 || (step > 0 && a - ahead_last > step);
      chain->look_ahead(g, c, a, cut, &*ahead_cam);
      ahead_cam = c;
      ahead_last = a;
    }
  };
  std::future<Loaded> next = std::async(std::launch::async, load, order.front());
  std::future<Delivery> delivering;  // the previous frame's
  std::string first_path;
  OIIO::ImageSpec first_spec;
  try {
    for (size_t k = 0; k < order.size(); ++k) {
      const auto t0 = Clock::now();
      const int frame = order[k];
      const bool history_only = k >= plan_.preroll.size() && done.count(frame) > 0;
      const bool preroll = k < plan_.preroll.size() || history_only;
      Loaded cur = next.get();
      auto read_next = [&] {
        if (k + 1 < order.size()) next = std::async(std::launch::async, load, order[k + 1]);
      };
      if (overlap) read_next();
      const io::InputFrame& in = cur.in;
      if (k == 0) {
        first_spec = in.spec;
        first_path = in.path;
      } else {
        require_same_size(in, first_spec, first_path);  // the file changed since the start
      }
      if (cur.zero.count > 0 && hooks.warning) {
        const size_t i = cur.zero.first;
        std::ostringstream s;
        s << in.where() << ": " << cur.zero.count << " pixel" << (cur.zero.count > 1 ? "s" : "")
          << " with a zero-length normal, the first at (" << i % size_t(in.spec.width) << ", "
          << i / size_t(in.spec.width) << "), taken as background";
        hooks.warning(frame, s.str());
      }
      // A missing frame in between: its history would be two frames old, and wrong where
      // anything moved.
      std::string gap;
      if (chain && k > 0 && order[k] - order[k - 1] > step) {
        const int a = order[k - 1] + step, b = frame - step;
        gap = a == b ? "frame " + std::to_string(a) + " missing"
                     : "frames " + std::to_string(a) + "-" + std::to_string(b) + " missing";
      }
      const auto t_compute = Clock::now();
      TemporalReport rep;
      std::optional<RadianceCache> pano;
      if (cur.pano.pixels() > 0) {
        if (chain) {
          chain->set_panorama(cur.pano, frame);
        } else {
          pano.emplace(1);
          pano->set_panorama(cur.pano, float(p_.background_depth), frame);
        }
        cur.pano = GBuffer{};
      }
      look_ahead(frame, cur.cam);
      if (!calibration_.empty()) {
        const double s = calibrated_scale(frame, cur.g, cur.cam);
        if (chain) {
          chain->set_unseen_scale(s);
          chain->set_fill_tiles(tiles.empty() ? nullptr : &tiles);
        }
        single.unseen_scale = s;
      }
      AoFrame result =
          chain ? chain->process(std::move(cur.g), cur.cam, frame,
                                 plan_.cuts.count(frame) > 0 || !gap.empty(), environment, &rep)
                : (cur.g.unpack(),
                   compute_ao_frame(cur.g, cur.cam, single, environment, pano ? &*pano : nullptr,
                                    frame, tiles.empty() ? nullptr : &tiles));
      if (!gap.empty() && rep.cut) rep.cut_reason = gap;
      const double compute_ms = ms(t_compute, Clock::now());
      if (!overlap && preroll) read_next();
      if (rep.cut && hooks.cut) hooks.cut(frame, rep);
      if (history_only) {
        if (hooks.history_only)
          hooks.history_only(frame, std::chrono::duration<double>(Clock::now() - t0).count());
        continue;
      }
      if (preroll) {
        if (hooks.preroll_done)
          hooks.preroll_done(frame, k + 1, plan_.preroll.size(),
                             std::chrono::duration<double>(Clock::now() - t0).count());
        continue;
      }
      Delivery d{std::make_unique<io::InputFrame>(std::move(cur.in)), {}};
      FrameResult& r = d.result;
      r.frame = frame;
      r.index = size_t(std::lower_bound(plan_.frames.begin(), plan_.frames.end(), frame) -
                       plan_.frames.begin()) +
                1;
      r.input = d.input.get();
      r.camera = cur.cam;
      r.outputs = std::move(result);
      r.report = rep;
      r.temporal = bool(chain);
      r.times = {cur.read_ms, cur.camera_ms, compute_ms, 0};
      r.started = t0;
      if (delivering.valid()) finish(delivering);  // the previous frame's
      delivering = std::async(std::launch::async, deliver, std::move(d));
      if (!overlap) {
        finish(delivering);
        read_next();
      }
    }
    if (delivering.valid()) finish(delivering);
  } catch (...) {
    // Nothing may still be running on this job's data when the error leaves it.
    if (delivering.valid()) delivering.wait();
    if (next.valid()) next.wait();
    throw;
  }
}

int sequence_step(const std::vector<int>& frames) {
  int step = 0;
  for (size_t k = 1; k < frames.size(); ++k)
    if (frames[k] > frames[k - 1] && (step == 0 || frames[k] - frames[k - 1] < step))
      step = frames[k] - frames[k - 1];
  return step;
}

}  // namespace hbil::pipeline
