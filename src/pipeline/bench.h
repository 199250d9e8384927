// bench.h: speed against accuracy on a user's own shot (`hbil bench`). Each configuration
// (a preset with --set and --sweep values) runs over the frames as `hbil run` would; each
// delivered frame's layers are compared with references (layer expressions over reference
// files), and the stages are timed. Renders of the same frames at several sample counts,
// with the render time their header records, give the path tracer's curve on the same axes
// and the equal-error speedup: the renderer's time at a configuration's composite error
// (interpolated on its curve) over the configuration's time.
#pragma once

#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "hbil/error_stats.h"
#include "hbil/params.h"
#include "io/layer_expr.h"

namespace hbil::pipeline {

// --ref LAYER[@TAG]=PATTERN:EXPR: hbil's layer LAYER against EXPR over the files of PATTERN
// (frame pattern or one file). The figures are reported under `name` (LAYER, or LAYER@TAG
// when one layer is judged against several references: indirect@1bounce, indirect@8bounce).
struct BenchReference {
  std::string name, layer, pattern, expr;
};
// Throws Error(Exit::usage) naming the option.
BenchReference parse_bench_reference(const std::string& text);

// --render PATTERN[:EXPR]: a path-traced render of the same frames (EXPR, default
// "Combined", compared with the composite's reference).
struct BenchRender {
  std::string pattern, expr = "Combined";
};
BenchRender parse_bench_render(const std::string& text);

// Blender's render time, "MM:SS.ss" or "HH:MM:SS.ss" (cycles.<ViewLayer>.render_time), or
// plain seconds, in seconds; negative when the text is none of these.
double parse_render_time(const std::string& text);

struct BenchConfig {
  std::string name;
  Params params;
};

// The configurations: each base (name, parameters) for every combination of the sweeps
// ("key=v1,v2,..."; values as --set takes them), named "<base> key=v ...". Throws
// Error(Exit::usage) for a malformed sweep, Error(Exit::preset) for a value --set refuses.
std::vector<BenchConfig> expand_sweeps(const std::vector<BenchConfig>& bases,
                                       const std::vector<std::string>& sweeps);

struct BenchSettings {
  std::string shot;    // input frame pattern or one file
  std::string frames;  // a frame list (io::parse_frame_list) or "" (every frame)
  std::vector<BenchConfig> configs;
  std::vector<BenchReference> refs;
  std::vector<BenchRender> renders;
  int runs = 1;  // timed runs per configuration, alternated; medians reported
  io::MaskSpec mask;
  bool stability = false;  // also the stability figures (stability.h), on the first --ref
                           // layer that is composite, indirect or irradiance, else the first
};

struct StageTimes {
  double read_ms = 0, camera_ms = 0, compute_ms = 0, write_ms = 0;
};

// `hbil bench --stability` (stability.h defines each figure); -1: not measured.
struct StabilityFigures {
  std::string layer;  // the layer judged
  double flicker = -1;
  double revealed_rmse = -1, other_rmse = -1, revealed_share = -1;
  bool cut_detected = false;
  int cut_recovery_frames = -1;  // -1: not measured (a single frame) or not within the run
  double edge_rmse = -1, interior_rmse = -1;
  double thin_rmse = -1, rest_rmse = -1, thin_share = -1;
  bool zero_normals_finite = false;
  std::string bad_input;  // what each injected non-finite input did ("refused (exit 5)" ...)
  bool robust = false;    // zero normals finite and every non-finite input refused
};

struct ConfigResult {
  std::string name;
  Params params;
  StageTimes times;                 // medians over frames and runs
  std::vector<double> run_seconds;  // each run's wall clock per frame
  double seconds_per_frame = 0;     // median of run_seconds
  // With Params::calibration: the calibration renders' own time (their headers' render
  // time, as for --render) over the frames, part of what the configuration costs; -1 where
  // a calibration render has none (then not counted).
  double calibration_seconds = 0;
  // A calibration was found and used (Params::calibration "auto" may find none).
  bool calibrated = false;
  // What a frame costs: seconds_per_frame and the calibration renders' share. The Pareto
  // fronts, the chart and the equal-error speedup take this.
  double cost_per_frame() const { return seconds_per_frame + std::max(0.0, calibration_seconds); }
  // By reference name (BenchReference::name):
  std::map<std::string, ErrorStats> errors;         // over all frames
  std::map<std::string, std::vector<double>> psnr;  // per frame
  std::map<std::string, bool> pareto;               // on that reference's front
  // Frame-to-frame change (temporal_change), of hbil's layer and of its reference; -1 for
  // a single frame.
  std::map<std::string, double> change, reference_change;
  std::vector<std::pair<int, std::string>> cuts;  // frames that dropped history, and why
  bool has_stability = false;
  StabilityFigures stability;
  double speedup = 0;         // the render's time at equal composite error / ours; 0: none
  std::string speedup_bound;  // "" (interpolated), ">" or "<" (beyond the render curve)
};

struct RenderResult {
  std::string pattern;
  int samples = 0;
  double seconds_per_frame = 0;  // the header's render time, mean over frames
  ErrorStats error;              // against the composite's reference
};

struct BenchResult {
  std::string shot;
  std::vector<int> frames;
  std::vector<std::string> layers;      // reference names, in --ref order
  std::string composite = "composite";  // the name of the composite's reference
  std::vector<ConfigResult> configs;
  std::vector<RenderResult> renders;  // by render time
  std::string machine;                // cores, load
};

struct FrameResult;  // sequence_job.h

// Frame-to-frame change of an image sequence: for each frame after the first, the sum over
// its valid pixels and channels of |x_k - x_(k-1)| over the sum of |x_k|; the mean over
// frames. A static camera's flicker; on a moving camera, to be set against the reference's.
class TemporalChange {
 public:
  // planes: the channels compared; valid: the pixels that count in this frame.
  void add(std::vector<std::vector<float>> planes, const std::vector<unsigned char>& valid);
  double value() const { return terms_ ? sum_ / terms_ : -1; }

 private:
  std::vector<std::vector<float>> prev_;
  double sum_ = 0;
  int terms_ = 0;
};

// A computed frame's layer `ref.layer` against its reference (the file of ref.pattern for the
// frame), on R, G, B, over the pixels `mask` keeps (and `region`, when given).
// `keep_planes`: the comparison keeps the compared channels and the valid pixels.
io::LayerComparison compare_with_reference(const FrameResult& fr, const Params& p,
                                           const BenchReference& ref, const io::MaskSpec& mask,
                                           const std::vector<unsigned char>* region = nullptr,
                                           bool keep_planes = false);

// Measures every configuration's errors (one run, untimed), then times it `runs` times,
// alternating the configurations, as `hbil run --no-display` computing the layers judged
// (the EXRs are written to a scratch folder and removed). `progress` gets a line per run. Throws
// hbil::Error as `hbil run` and `hbil compare` do.
BenchResult run_bench(const BenchSettings& s,
                      const std::function<void(const std::string&)>& progress = {});

// The configurations that no other beats on both time and PSNR of `layer`.
void mark_pareto(BenchResult& r);
// Speedups at equal composite error against the render curve.
void equal_error_speedups(BenchResult& r);

// DIR/bench.json, DIR/bench.csv, DIR/chart.svg, DIR/chart.png. Throws Error(Exit::output).
void write_bench(const BenchResult& r, const std::string& dir);

}  // namespace hbil::pipeline
