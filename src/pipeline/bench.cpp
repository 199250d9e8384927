// bench.cpp: see bench.h.
#include "pipeline/bench.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "hbil/error.h"
#include "io/exr_output.h"
#include "pipeline/chart.h"
#include "pipeline/sequence_job.h"
#include "pipeline/stability.h"

namespace hbil::pipeline {

namespace fs = std::filesystem;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Splits at commas outside brackets, braces and quotes ("a,[1,2],b" -> a, [1,2], b).
std::vector<std::string> split_values(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  bool quoted = false;
  for (char c : s) {
    if (c == '"') quoted = !quoted;
    if (!quoted && (c == '[' || c == '{')) ++depth;
    if (!quoted && (c == ']' || c == '}')) --depth;
    if (c == ',' && depth == 0 && !quoted) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

// The header attribute whose name starts with "cycles." and ends with `suffix`.
std::string cycles_attribute(const OIIO::ImageSpec& spec, const std::string& suffix) {
  for (const OIIO::ParamValue& a : spec.extra_attribs) {
    const std::string n = a.name().string();
    if (n.rfind("cycles.", 0) == 0 && n.size() > suffix.size() &&
        n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0)
      return a.get_string();
  }
  return "";
}

std::string machine_description() {
  std::string load = "?";
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  if (in >> a >> b >> c) {
    char s[64];
    std::snprintf(s, sizeof s, "%.2f %.2f %.2f", a, b, c);
    load = s;
  }
  return std::to_string(std::thread::hardware_concurrency()) + " cores, load " + load;
}

nlohmann::json num_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

nlohmann::json stats_json(const ErrorStats& s) {
  return {{"pixels", s.count},
          {"rmse", s.rmse()},
          {"mean_error", s.mean_error()},
          {"psnr", num_or_null(s.psnr())},
          {"relative_rmse", num_or_null(s.relative_rmse())},
          {"energy", num_or_null(s.energy_ratio())}};
}

// The calibration renders' own time from their headers, over `frames` frames; -1 where one
// has none.
double calibration_render_seconds(const Calibration& c, size_t frames) {
  double sum = 0;
  for (const std::string& path : c.paths()) {
    io::ImageFile f(path);
    const double t = parse_render_time(cycles_attribute(f.spec(), ".render_time"));
    if (t < 0) return -1;
    sum += t + 0.005;  // truncated to 10 ms, as for --render
  }
  return frames ? sum / double(frames) : 0;
}

}  // namespace

double parse_render_time(const std::string& t) {
  double total = 0;
  size_t start = 0;
  for (;;) {
    const size_t colon = t.find(':', start);
    const std::string part = t.substr(start, colon == std::string::npos ? colon : colon - start);
    try {
      size_t used = 0;
      const double v = std::stod(part, &used);
      if (used != part.size() || v < 0) return -1;
      total = total * 60 + v;
    } catch (const std::exception&) {
      return -1;
    }
    if (colon == std::string::npos) return total;
    start = colon + 1;
  }
}

BenchReference parse_bench_reference(const std::string& text) {
  const size_t eq = text.find('=');
  const size_t colon = text.rfind(':');
  if (eq == std::string::npos || eq == 0 || colon == std::string::npos || colon < eq + 2 ||
      colon + 1 == text.size())
    throw Error(Exit::usage, "--ref " + text +
                                 ": expected LAYER[@TAG]=PATTERN:EXPRESSION, e.g. "
                                 "ao='ref/frame_####.exr:AO'");
  BenchReference r{text.substr(0, eq), "", text.substr(eq + 1, colon - eq - 1),
                   text.substr(colon + 1)};
  const size_t at = r.name.find('@');
  r.layer = r.name.substr(0, at);
  if (at != std::string::npos &&
      (at + 1 == r.name.size() || r.name.find_first_of("@,\"= ", at + 1) != std::string::npos))
    throw Error(Exit::usage,
                "--ref " + text + ": the tag after '@' must be a word without @ , \" = or spaces");
  const auto& known = known_outputs();
  if (std::find(known.begin(), known.end(), r.layer) == known.end() || r.layer == "history")
    throw Error(Exit::usage, "--ref " + text + ": '" + r.layer +
                                 "' is not one of hbil's layers (ao, bentcone, irradiance, "
                                 "indirect, farfield, composite)");
  io::parse_layer_expr("--ref " + r.name, r.expr);  // a malformed expression: usage error
  return r;
}

BenchRender parse_bench_render(const std::string& text) {
  BenchRender r;
  const size_t colon = text.rfind(':');
  // A colon that ends the pattern's file name part (".exr:Combined") separates the expression.
  if (colon != std::string::npos && text.find('/', colon) == std::string::npos &&
      colon + 1 < text.size()) {
    r.pattern = text.substr(0, colon);
    r.expr = text.substr(colon + 1);
  } else {
    r.pattern = text;
  }
  if (r.pattern.empty()) throw Error(Exit::usage, "--render " + text + ": no file pattern");
  io::parse_layer_expr("--render", r.expr);
  return r;
}

std::vector<BenchConfig> expand_sweeps(const std::vector<BenchConfig>& bases,
                                       const std::vector<std::string>& sweeps) {
  std::vector<BenchConfig> out = bases;
  for (const std::string& sweep : sweeps) {
    const size_t eq = sweep.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == sweep.size())
      throw Error(Exit::usage,
                  "--sweep " + sweep + ": expected key=v1,v2,... (e.g. gather_radius=2,4,8)");
    const std::string key = sweep.substr(0, eq);
    std::vector<BenchConfig> next;
    for (const BenchConfig& c : out)
      for (const std::string& v : split_values(sweep.substr(eq + 1))) {
        if (v.empty()) throw Error(Exit::usage, "--sweep " + sweep + ": an empty value");
        next.push_back({c.name + " " + key + "=" + v, apply_set(c.params, key + "=" + v)});
      }
    out = std::move(next);
  }
  return out;
}

void mark_pareto(BenchResult& r) {
  for (const std::string& layer : r.layers)
    for (ConfigResult& a : r.configs) {
      const double ta = a.cost_per_frame(), pa = a.errors[layer].psnr();
      bool beaten = false;
      for (ConfigResult& b : r.configs) {
        if (&a == &b) continue;
        const double tb = b.cost_per_frame(), pb = b.errors[layer].psnr();
        if (tb <= ta && pb >= pa && (tb < ta || pb > pa)) beaten = true;
      }
      a.pareto[layer] = !beaten;
    }
}

void equal_error_speedups(BenchResult& r) {
  if (r.renders.empty()) return;
  std::vector<std::pair<double, double>> curve;  // seconds, PSNR; by seconds
  for (const RenderResult& x : r.renders)
    if (x.seconds_per_frame > 0 && std::isfinite(x.error.psnr()))
      curve.emplace_back(x.seconds_per_frame, x.error.psnr());
  std::sort(curve.begin(), curve.end());
  if (curve.empty()) return;
  for (ConfigResult& c : r.configs) {
    const auto it = c.errors.find(r.composite);
    if (it == c.errors.end() || c.cost_per_frame() <= 0) continue;
    const double p = it->second.psnr();
    c.speedup_bound.clear();
    // The first render at or above our PSNR; log time linear in PSNR between neighbours.
    size_t i = 0;
    while (i < curve.size() && curve[i].second < p) ++i;
    double t;
    if (i == curve.size()) {
      t = curve.back().first;
      c.speedup_bound = ">";
    } else if (i == 0) {
      t = curve.front().first;
      c.speedup_bound = "<";
    } else {
      const auto [t0, p0] = curve[i - 1];
      const auto [t1, p1] = curve[i];
      const double u = p1 > p0 ? (p - p0) / (p1 - p0) : 1.0;
      t = std::exp(std::log(t0) + u * (std::log(t1) - std::log(t0)));
    }
    c.speedup = t / c.cost_per_frame();
  }
}

void TemporalChange::add(std::vector<std::vector<float>> planes,
                         const std::vector<unsigned char>& valid) {
  if (prev_.size() == planes.size()) {
    double d = 0, m = 0;
    for (size_t c = 0; c < planes.size(); ++c) {
      const std::vector<float>& a = planes[c];
      const std::vector<float>& b = prev_[c];
      if (a.size() != b.size()) return;  // a different size: no change measured
      for (size_t i = 0; i < a.size() && i < valid.size(); ++i)
        if (valid[i]) {
          d += std::fabs(double(a[i]) - b[i]);
          m += std::fabs(double(a[i]));
        }
    }
    if (m > 0) sum_ += d / m, ++terms_;
  }
  prev_ = std::move(planes);
}

io::LayerComparison compare_with_reference(const FrameResult& fr, const Params& p,
                                           const BenchReference& ref, const io::MaskSpec& mask,
                                           const std::vector<unsigned char>* region,
                                           bool keep_planes) {
  std::vector<io::MemoryChannels::Channel> chans;
  for (const io::OutputChannel& oc : io::output_plan(fr.outputs, p))
    chans.push_back({oc.name, oc.src, oc.stride});
  // At the input's data window, so that an overscan's output is judged over the reference's.
  const bool windowed = fr.input && fr.input->spec.width == fr.outputs.width &&
                        fr.input->spec.height == fr.outputs.height;
  io::MemoryChannels test("hbil's frame " + std::to_string(fr.frame), fr.outputs.width,
                          fr.outputs.height, std::move(chans), windowed ? fr.input->spec.x : 0,
                          windowed ? fr.input->spec.y : 0);
  io::ImageFile file(io::FramePattern(ref.pattern).path(fr.frame));
  return io::compare_layers(test, io::parse_layer_expr("layer", ref.layer), "layer", ref.layer,
                            file, io::parse_layer_expr("--ref " + ref.name, ref.expr),
                            "--ref " + ref.name, ref.expr, mask, true, region, keep_planes);
}

BenchResult run_bench(const BenchSettings& s,
                      const std::function<void(const std::string&)>& progress) {
  if (s.configs.empty()) throw Error(Exit::usage, "bench: no configuration to run");
  if (s.refs.empty())
    throw Error(Exit::usage, "bench: give at least one --ref LAYER=PATTERN:EXPRESSION");
  const SequencePlan plan = plan_sequence(s.shot, s.frames, 0, "");
  BenchResult r;
  r.shot = s.shot;
  r.frames = plan.frames;
  r.machine = machine_description();
  const BenchReference* composite_ref = nullptr;
  std::vector<std::string> outputs;  // the layers judged, each once
  for (const BenchReference& ref : s.refs) {
    if (std::find(r.layers.begin(), r.layers.end(), ref.name) != r.layers.end())
      throw Error(Exit::usage, "--ref " + ref.name + " is given twice");
    r.layers.push_back(ref.name);
    if (std::find(outputs.begin(), outputs.end(), ref.layer) == outputs.end())
      outputs.push_back(ref.layer);
    io::parse_layer_expr("--ref " + ref.name, ref.expr);  // malformed: a usage error now
    // The composite's reference: plain "composite", else the first tagged one.
    if (ref.layer == "composite" && (!composite_ref || ref.name == "composite"))
      composite_ref = &ref;
  }
  if (composite_ref) r.composite = composite_ref->name;
  if (!s.renders.empty() && !composite_ref)
    throw Error(Exit::usage,
                "--render needs the composite's reference: --ref composite=PATTERN:EXPRESSION");
  // Each configuration computes the layers it is judged on, and no other.
  std::vector<BenchConfig> configs = s.configs;
  for (BenchConfig& c : configs) {
    c.params.outputs = outputs;
    validate(c.params, "bench configuration " + c.name);
  }
  r.configs.resize(configs.size());
  // "auto" resolved once per configuration, so that its runs do not read the shot's first
  // frame again (the results keep the configurations as given).
  std::vector<Params> resolved;
  for (const BenchConfig& c : configs) resolved.push_back(SequenceJob(plan, c.params).params());
  // Errors first, once per configuration (they do not change from run to run).
  for (size_t ci = 0; ci < configs.size(); ++ci) {
    const BenchConfig& c = configs[ci];
    ConfigResult& cr = r.configs[ci];
    cr.name = c.name;
    cr.params = c.params;
    const SequenceJob job(plan, resolved[ci]);
    cr.calibrated = !job.calibration().empty();
    cr.calibration_seconds = calibration_render_seconds(job.calibration(), plan.frames.size());
    std::vector<TemporalChange> ours(s.refs.size()), theirs(s.refs.size());
    SequenceJob::Hooks hooks;
    hooks.deliver = [&](FrameResult& fr) {
      for (size_t k = 0; k < s.refs.size(); ++k) {
        const BenchReference& ref = s.refs[k];
        io::LayerComparison lc =
            compare_with_reference(fr, job.params(), ref, s.mask, nullptr, true);
        cr.errors[ref.name].add(lc.overall);
        cr.psnr[ref.name].push_back(lc.overall.psnr());
        ours[k].add(std::move(lc.test_planes), lc.valid);
        theirs[k].add(std::move(lc.ref_planes), lc.valid);
      }
    };
    hooks.cut = [&](int frame, const TemporalReport& t) {
      cr.cuts.emplace_back(frame, t.cut_reason);
    };
    job.run(hooks, Overlap::off);
    for (size_t k = 0; k < s.refs.size(); ++k) {
      cr.change[s.refs[k].name] = ours[k].value();
      cr.reference_change[s.refs[k].name] = theirs[k].value();
    }
    if (progress) {
      std::string text = "bench: " + c.name + " (" + std::to_string(ci + 1) + "/" +
                         std::to_string(configs.size()) + "):";
      char line[128];
      for (const std::string& layer : r.layers) {
        std::snprintf(line, sizeof line, " %s %.2f dB", layer.c_str(), cr.errors[layer].psnr());
        text += line;
      }
      progress(text);
    }
  }
  // Then the timed runs, as `hbil run --no-display` with the layers judged: reading and
  // writing overlap the computing, each EXR is written (to a scratch folder, then removed);
  // the configurations alternate run by run, so that a shared machine's load falls on all.
  const fs::path scratch = fs::temp_directory_path() / ("hbil-bench-" + std::to_string(::getpid()));
  struct Scratch {
    fs::path dir;
    ~Scratch() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } scratch_guard{scratch};
  std::vector<std::vector<StageTimes>> stage_samples(configs.size());
  for (int run = 0; run < s.runs; ++run)
    for (size_t ci = 0; ci < configs.size(); ++ci) {
      ConfigResult& cr = r.configs[ci];
      const SequenceJob job(plan, resolved[ci]);
      configure_heap(job.first().spec.width, job.first().spec.height);  // as run does
      const io::FramePattern out((scratch / "frame_####.exr").string());
      SequenceJob::Hooks hooks;
      hooks.deliver = [&](FrameResult& fr) {
        const std::string tmp = io::write_temporary(out.path(fr.frame), fr.outputs, fr.input->spec,
                                                    job.params(), fr.camera);
        std::error_code ec;
        fs::remove(tmp, ec);
      };
      hooks.delivered = [&](const FrameResult& fr) {
        stage_samples[ci].push_back(
            {fr.times.read_ms, fr.times.camera_ms, fr.times.compute_ms, fr.times.deliver_ms});
      };
      const auto t0 = std::chrono::steady_clock::now();
      job.run(hooks, Overlap::automatic);
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      cr.run_seconds.push_back(wall / double(plan.frames.size()));
      if (progress) {
        char line[512];
        std::snprintf(line, sizeof line, "bench: %s, run %d/%d: %.3f s per frame", cr.name.c_str(),
                      run + 1, s.runs, cr.run_seconds.back());
        progress(line);
      }
    }
  for (size_t ci = 0; ci < configs.size(); ++ci) {
    ConfigResult& cr = r.configs[ci];
    std::vector<double> rd, cm, cp, wr;
    for (const StageTimes& t : stage_samples[ci])
      rd.push_back(t.read_ms), cm.push_back(t.camera_ms), cp.push_back(t.compute_ms),
          wr.push_back(t.write_ms);
    cr.times = {median(rd), median(cm), median(cp), median(wr)};
    cr.seconds_per_frame = median(cr.run_seconds);
  }
  // Stability, per configuration, on one colour layer (else the first judged).
  if (s.stability) {
    const BenchReference* judged = &s.refs.front();
    for (const char* l : {"composite", "indirect", "irradiance"}) {
      auto it = std::find_if(s.refs.begin(), s.refs.end(),
                             [&](const BenchReference& r) { return r.layer == l; });
      if (it != s.refs.end()) {
        judged = &*it;
        break;
      }
    }
    for (size_t ci = 0; ci < configs.size(); ++ci) {
      const fs::path dir = scratch / ("stability-" + std::to_string(ci));
      r.configs[ci].stability =
          measure_stability(s, {configs[ci].name, s.configs[ci].params}, *judged, dir.string());
      r.configs[ci].has_stability = true;
      std::error_code ec;
      fs::remove_all(dir, ec);
      if (progress) {
        const StabilityFigures& f = r.configs[ci].stability;
        char line[512];
        std::snprintf(line, sizeof line,
                      "bench: %s stability (%s): flicker %.5f, revealed/other RMSE %.4f/%.4f, cut "
                      "%s, edge/interior %.4f/%.4f, thin/rest %.4f/%.4f, %s",
                      configs[ci].name.c_str(), f.layer.c_str(), f.flicker, f.revealed_rmse,
                      f.other_rmse, f.cut_detected ? "detected" : "not detected", f.edge_rmse,
                      f.interior_rmse, f.thin_rmse, f.rest_rmse,
                      f.robust ? "robust" : "NOT robust");
        progress(line);
      }
    }
  }
  // The renderer's curve: each render's time from its header and its composite error.
  for (const BenchRender& br : s.renders) {
    RenderResult rr;
    rr.pattern = br.pattern;
    const io::LayerExpr e = io::parse_layer_expr("--render", br.expr);
    const io::LayerExpr ce =
        io::parse_layer_expr("--ref " + composite_ref->name, composite_ref->expr);
    double seconds = 0;
    for (int f : plan.frames) {
      io::ImageFile render(io::FramePattern(br.pattern).path(f));
      const std::string t = cycles_attribute(render.spec(), ".render_time");
      const double sec = parse_render_time(t);
      if (sec < 0)
        throw Error(Exit::input, render.name() +
                                     ": no render time in the header (Blender writes "
                                     "cycles.<ViewLayer>.render_time)");
      // Blender writes it truncated to 10 ms: half of that is added (unbiased for the mean).
      seconds += sec + 0.005;
      const std::string samples = cycles_attribute(render.spec(), ".samples");
      rr.samples = samples.empty() ? 0 : std::atoi(samples.c_str());
      io::ImageFile ref(io::FramePattern(composite_ref->pattern).path(f));
      rr.error.add(io::compare_layers(render, e, "--render", br.expr, ref, ce,
                                      "--ref " + composite_ref->name, composite_ref->expr, s.mask,
                                      true)
                       .overall);
    }
    rr.seconds_per_frame = seconds / double(plan.frames.size());
    if (progress) {
      char line[512];
      std::snprintf(line, sizeof line, "bench: render %s (%d samples): %.3f s per frame, %.2f dB",
                    br.pattern.c_str(), rr.samples, rr.seconds_per_frame, rr.error.psnr());
      progress(line);
    }
    r.renders.push_back(rr);
  }
  std::sort(r.renders.begin(), r.renders.end(), [](const RenderResult& a, const RenderResult& b) {
    return a.seconds_per_frame < b.seconds_per_frame;
  });
  mark_pareto(r);
  equal_error_speedups(r);
  return r;
}

void write_bench(const BenchResult& r, const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error(Exit::output, dir + ": cannot create folder: " + ec.message());
  auto write_file = [&](const std::string& name, const std::string& text) {
    io::write_file((fs::path(dir) / name).string(), text);
  };
  // JSON: everything.
  nlohmann::json j;
  j["shot"] = r.shot;
  j["frames"] = r.frames;
  j["machine"] = r.machine;
  j["layers"] = r.layers;
  j["seconds_per_frame"] =
      "wall clock per frame as hbil run --no-display with the layers judged (reading and "
      "writing overlapping the computing), median of the runs; stages_ms: medians over frames "
      "and runs; calibration_render_seconds_per_frame: the calibration renders' own time from "
      "their headers over the frames (null: a render without one), added to seconds_per_frame "
      "for the Pareto fronts, the chart and equal_error_speedup";
  j["configurations"] = nlohmann::json::array();
  for (const ConfigResult& c : r.configs) {
    nlohmann::json jc;
    jc["name"] = c.name;
    jc["parameters"] = to_json(c.params);
    jc["seconds_per_frame"] = c.seconds_per_frame;
    if (c.calibrated)
      jc["calibration_render_seconds_per_frame"] = c.calibration_seconds >= 0
                                                       ? nlohmann::json(c.calibration_seconds)
                                                       : nlohmann::json(nullptr);
    jc["runs"] = c.run_seconds;
    jc["cuts"] = nlohmann::json::array();
    for (const auto& [frame, why] : c.cuts)
      jc["cuts"].push_back({{"frame", frame}, {"reason", why}});
    jc["stages_ms"] = {{"read", c.times.read_ms},
                       {"camera", c.times.camera_ms},
                       {"compute", c.times.compute_ms},
                       {"write", c.times.write_ms}};
    for (const std::string& layer : r.layers) {
      nlohmann::json jl = stats_json(c.errors.at(layer));
      jl["pareto"] = c.pareto.at(layer);
      jl["psnr_per_frame"] = nlohmann::json::array();
      for (double v : c.psnr.at(layer)) jl["psnr_per_frame"].push_back(num_or_null(v));
      const double ch = c.change.at(layer), rch = c.reference_change.at(layer);
      jl["change"] = ch >= 0 ? nlohmann::json(ch) : nlohmann::json(nullptr);
      jl["reference_change"] = rch >= 0 ? nlohmann::json(rch) : nlohmann::json(nullptr);
      jc["layers"][layer] = jl;
    }
    if (c.has_stability) {
      const StabilityFigures& f = c.stability;
      jc["stability"] = {{"layer", f.layer},
                         {"flicker", f.flicker},
                         {"revealed_rmse", f.revealed_rmse},
                         {"other_rmse", f.other_rmse},
                         {"revealed_share", f.revealed_share},
                         {"cut_detected", f.cut_detected},
                         {"cut_recovery_frames", f.cut_recovery_frames},
                         {"edge_rmse", f.edge_rmse},
                         {"interior_rmse", f.interior_rmse},
                         {"thin_rmse", f.thin_rmse},
                         {"rest_rmse", f.rest_rmse},
                         {"thin_share", f.thin_share},
                         {"zero_normals_finite", f.zero_normals_finite},
                         {"non_finite_input", f.bad_input},
                         {"robust", f.robust}};
    }
    if (c.speedup > 0) {
      jc["equal_error_speedup"] = c.speedup;
      if (!c.speedup_bound.empty()) jc["equal_error_speedup_bound"] = c.speedup_bound;
    }
    j["configurations"].push_back(jc);
  }
  j["renders"] = nlohmann::json::array();
  for (const RenderResult& x : r.renders)
    j["renders"].push_back({{"pattern", x.pattern},
                            {"samples", x.samples},
                            {"seconds_per_frame", x.seconds_per_frame},
                            {"composite", stats_json(x.error)}});
  write_file("bench.json", j.dump(2) + "\n");
  // CSV: one row per configuration and layer, then one per render.
  std::string csv =
      "kind,name,layer,seconds_per_frame,read_ms,camera_ms,compute_ms,write_ms,rmse,mean_error,"
      "psnr,"
      "relative_rmse,energy,pareto,equal_error_speedup,change,reference_change\n";
  auto f = [](double v) {
    char b[32];
    if (!std::isfinite(v)) return std::string(std::isinf(v) && v > 0 ? "inf" : "");
    std::snprintf(b, sizeof b, "%.6g", v);
    return std::string(b);
  };
  auto quoted = [](const std::string& s) {
    std::string o = "\"";
    for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
    return o + "\"";
  };
  for (const ConfigResult& c : r.configs)
    for (const std::string& layer : r.layers) {
      const ErrorStats& e = c.errors.at(layer);
      csv += "hbil," + quoted(c.name) + "," + layer + "," + f(c.seconds_per_frame) + "," +
             f(c.times.read_ms) + "," + f(c.times.camera_ms) + "," + f(c.times.compute_ms) + "," +
             f(c.times.write_ms) + "," + f(e.rmse()) + "," + f(e.mean_error()) + "," + f(e.psnr()) +
             "," + f(e.relative_rmse()) + "," + f(e.energy_ratio()) + "," +
             (c.pareto.at(layer) ? "1" : "0") + "," +
             (layer == r.composite && c.speedup > 0 ? c.speedup_bound + f(c.speedup) : "") + "," +
             f(c.change.at(layer)) + "," + f(c.reference_change.at(layer)) + "\n";
    }
  for (const RenderResult& x : r.renders)
    csv += "render," + quoted(x.pattern + " (" + std::to_string(x.samples) + " samples)") +
           ",composite," + f(x.seconds_per_frame) + ",,,,," + f(x.error.rmse()) + "," +
           f(x.error.mean_error()) + "," + f(x.error.psnr()) + "," + f(x.error.relative_rmse()) +
           "," + f(x.error.energy_ratio()) + ",,,,\n";
  write_file("bench.csv", csv);
  // Stability: one row per configuration.
  if (!r.configs.empty() && r.configs.front().has_stability) {
    std::string st =
        "name,layer,flicker,revealed_rmse,other_rmse,revealed_share,cut_detected,"
        "cut_recovery_frames,edge_rmse,interior_rmse,thin_rmse,rest_rmse,thin_share,"
        "zero_normals_finite,non_finite_input,robust\n";
    for (const ConfigResult& c : r.configs) {
      const StabilityFigures& x = c.stability;
      st += quoted(c.name) + "," + x.layer + "," + f(x.flicker) + "," + f(x.revealed_rmse) + "," +
            f(x.other_rmse) + "," + f(x.revealed_share) + "," + (x.cut_detected ? "1" : "0") + "," +
            std::to_string(x.cut_recovery_frames) + "," + f(x.edge_rmse) + "," +
            f(x.interior_rmse) + "," + f(x.thin_rmse) + "," + f(x.rest_rmse) + "," +
            f(x.thin_share) + "," + (x.zero_normals_finite ? "1" : "0") + "," +
            quoted(x.bad_input) + "," + (x.robust ? "1" : "0") + "\n";
    }
    write_file("stability.csv", st);
  }
  // The chart: a panel per layer, seconds per frame against PSNR; the Pareto front filled
  // and joined, the renders' curve on the composite's panel.
  std::vector<ChartPanel> panels;
  for (const std::string& layer : r.layers) {
    ChartPanel p{layer + ": speed against accuracy",
                 "seconds per frame (log)",
                 "PSNR (dB), higher is better",
                 true,
                 {}};
    ChartSeries front{"hbil, Pareto front", {0.10f, 0.35f, 0.75f}, false, true, {}},
        others{"hbil, dominated", {0.10f, 0.35f, 0.75f}, false, false, {}};
    std::vector<const ConfigResult*> order;
    for (const ConfigResult& c : r.configs) order.push_back(&c);
    std::sort(order.begin(), order.end(),
              [](auto a, auto b) { return a->cost_per_frame() < b->cost_per_frame(); });
    for (const ConfigResult* c : order) {
      ChartSeries::Point pt{c->cost_per_frame(), c->errors.at(layer).psnr(), c->name,
                            c->pareto.at(layer)};
      (c->pareto.at(layer) ? front : others).points.push_back(pt);
    }
    if (!others.points.empty())
      for (auto& pt : others.points) pt.filled = false;
    p.series.push_back(front);
    if (!others.points.empty()) p.series.push_back(others);
    if (layer == r.composite && !r.renders.empty()) {
      ChartSeries cy{"path tracer (render time)", {0.85f, 0.35f, 0.10f}, true, true, {}};
      for (const RenderResult& x : r.renders)
        cy.points.push_back({x.seconds_per_frame, x.error.psnr(),
                             x.samples > 0 ? std::to_string(x.samples) + " spp" : "", true});
      p.series.push_back(cy);
    }
    panels.push_back(p);
  }
  write_file("chart.svg", chart_svg(panels));
  write_chart_png(panels, (fs::path(dir) / "chart.png").string());
}

}  // namespace hbil::pipeline
