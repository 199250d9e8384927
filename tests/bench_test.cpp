// bench_test.cpp: `hbil bench` (pipeline/bench.h): option parsing, sweeps, the Pareto front
// and the equal-error speedup on made-up results with known answers, and a run on the
// room_poles sample whose errors must equal `hbil compare`'s on `hbil run`'s output.

#include "pipeline/bench.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hbil/error.h"
#include "pipeline/tune.h"
#include "test_util.h"

namespace hbil {
namespace {

using pipeline::BenchResult;
using pipeline::ConfigResult;
using pipeline::RenderResult;
using test::contains;
using test::expect_error;
namespace fs = std::filesystem;

// Statistics with a given MSE (so PSNR = -10 log10(mse)).
ErrorStats with_mse(double mse) {
  ErrorStats s;
  s.sum_sq = mse * 100;
  s.count = 100;
  return s;
}

// The path tracer's curve of the speedup tests: 1 s a frame at 20 dB, 2 s at 23 dB.
void add_render_curve(BenchResult& r) {
  for (auto [t, p] : {std::pair{2.0, 23.0}, std::pair{1.0, 20.0}}) {
    RenderResult x;
    x.seconds_per_frame = t;
    x.error = with_mse(std::pow(10.0, -p / 10));
    r.renders.push_back(x);
  }
}

ConfigResult config(const std::string& name, double seconds, double psnr) {
  ConfigResult c;
  c.name = name;
  c.seconds_per_frame = seconds;
  c.errors["composite"] = with_mse(std::pow(10.0, -psnr / 10));
  return c;
}

TEST(BenchOptions, ReferenceIsLayerPatternAndExpression) {
  const auto r = pipeline::parse_bench_reference("indirect=ref/f_####.exr:DiffCol*DiffInd");
  EXPECT_EQ(r.layer, "indirect");
  EXPECT_EQ(r.pattern, "ref/f_####.exr");
  EXPECT_EQ(r.expr, "DiffCol*DiffInd");
  // The last colon separates the expression: a path may hold colons.
  const auto c = pipeline::parse_bench_reference("ao=a:b/f.exr:AO");
  EXPECT_EQ(c.pattern, "a:b/f.exr");
  EXPECT_EQ(c.expr, "AO");
  for (const char* bad : {"ao", "ao=f.exr", "=f.exr:AO", "ao=f.exr:", "ao=:AO"})
    expect_error([&] { pipeline::parse_bench_reference(bad); }, Exit::usage, {"--ref"});
  expect_error([] { pipeline::parse_bench_reference("glow=f.exr:AO"); }, Exit::usage,
               {"'glow' is not one of hbil's layers"});
  expect_error([] { pipeline::parse_bench_reference("ao=f.exr:AO*(B"); }, Exit::usage,
               {"missing ')'"});
}

// A tag names a second reference for the same layer; the figures go under the whole name.
TEST(BenchOptions, TaggedReferenceJudgesTheSameLayerAgain) {
  const auto r = pipeline::parse_bench_reference("indirect@1bounce=b1/f_####.exr:DiffCol*DiffInd");
  EXPECT_EQ(r.name, "indirect@1bounce");
  EXPECT_EQ(r.layer, "indirect");
  EXPECT_EQ(r.pattern, "b1/f_####.exr");
  EXPECT_EQ(pipeline::parse_bench_reference("ao=f.exr:AO").name, "ao");
  for (const char* bad : {"indirect@=f.exr:X", "indirect@a b=f.exr:X", "indirect@a@b=f.exr:X"})
    expect_error([&] { pipeline::parse_bench_reference(bad); }, Exit::usage, {"the tag after"});
  expect_error([] { pipeline::parse_bench_reference("glow@x=f.exr:AO"); }, Exit::usage,
               {"'glow' is not one of hbil's layers"});
}

// Frame-to-frame change: sum |x_k - x_(k-1)| over sum |x_k| on the valid pixels, averaged.
TEST(BenchChange, KnownPlanes) {
  pipeline::TemporalChange c;
  EXPECT_EQ(c.value(), -1);  // nothing measured
  const std::vector<unsigned char> all = {1, 1}, first = {1, 0};
  c.add({{1, 1}, {1, 1}}, all);
  EXPECT_EQ(c.value(), -1);  // one frame: no change yet
  c.add({{2, 2}, {2, 2}}, all);
  EXPECT_DOUBLE_EQ(c.value(), 4.0 / 8.0);
  c.add({{2, 9}, {2, 9}}, first);  // the changed pixel is not valid: no change
  EXPECT_DOUBLE_EQ(c.value(), (0.5 + 0.0) / 2);
  c.add({{1, 9}, {3, 9}}, first);  // |1-2| + |3-2| over 1 + 3
  EXPECT_DOUBLE_EQ(c.value(), (0.5 + 0.0 + 0.5) / 3);
}

TEST(BenchOptions, RenderPatternAndExpression) {
  EXPECT_EQ(pipeline::parse_bench_render("r/spp8/f_####.exr").expr, "Combined");
  const auto r = pipeline::parse_bench_render("r/spp8/f_####.exr:Image");
  EXPECT_EQ(r.pattern, "r/spp8/f_####.exr");
  EXPECT_EQ(r.expr, "Image");
}

TEST(BenchOptions, RenderTimeAsBlenderWritesIt) {
  EXPECT_DOUBLE_EQ(pipeline::parse_render_time("01:21.59"), 81.59);
  EXPECT_DOUBLE_EQ(pipeline::parse_render_time("00:00.06"), 0.06);
  EXPECT_DOUBLE_EQ(pipeline::parse_render_time("1:02:03.5"), 3723.5);
  EXPECT_DOUBLE_EQ(pipeline::parse_render_time("2.25"), 2.25);
  for (const char* bad : {"", "abc", "01:xx", "-1", "1::2"})
    EXPECT_LT(pipeline::parse_render_time(bad), 0) << bad;
}

TEST(BenchSweeps, EveryCombinationNamedAndApplied) {
  const auto c = pipeline::expand_sweeps({{"default", Params{}}},
                                         {"slices=1,2,4", "method=\"horizon\",\"bitmask\""});
  ASSERT_EQ(c.size(), 6u);
  EXPECT_EQ(c[0].name, "default slices=1 method=\"horizon\"");
  EXPECT_EQ(c[5].name, "default slices=4 method=\"bitmask\"");
  EXPECT_EQ(c[2].params.slices, 2);
  EXPECT_EQ(c[2].params.method, "horizon");
  EXPECT_EQ(c[5].params.slices, 4);
  EXPECT_EQ(c[5].params.method, "bitmask");
  // Commas inside brackets belong to the value.
  const auto o =
      pipeline::expand_sweeps({{"d", Params{}}}, {"outputs=[\"ao\",\"bentcone\"],[\"ao\"]"});
  ASSERT_EQ(o.size(), 2u);
  EXPECT_EQ(o[0].params.outputs, (std::vector<std::string>{"ao", "bentcone"}));
  EXPECT_EQ(o[1].params.outputs, (std::vector<std::string>{"ao"}));
  expect_error(
      [] {
        pipeline::expand_sweeps({{"d", Params{}}}, {"slices"});
      },
      Exit::usage, {"--sweep slices", "key=v1,v2"});
  expect_error(
      [] {
        pipeline::expand_sweeps({{"d", Params{}}}, {"slices=1,,2"});
      },
      Exit::usage, {"empty value"});
  expect_error(
      [] {
        pipeline::expand_sweeps({{"d", Params{}}}, {"no_such_key=1"});
      },
      Exit::preset, {"no_such_key"});
}

TEST(BenchPareto, DominatedConfigurationsAreOffTheFront) {
  BenchResult r;
  r.layers = {"composite"};
  r.configs = {config("a", 1.0, 20), config("b", 2.0, 25), config("c", 3.0, 24),
               config("d", 0.5, 18), config("e", 1.0, 19)};
  pipeline::mark_pareto(r);
  EXPECT_TRUE(r.configs[0].pareto["composite"]);   // fastest at 20 dB
  EXPECT_TRUE(r.configs[1].pareto["composite"]);   // the most accurate
  EXPECT_FALSE(r.configs[2].pareto["composite"]);  // slower and worse than b
  EXPECT_TRUE(r.configs[3].pareto["composite"]);   // the fastest
  EXPECT_FALSE(r.configs[4].pareto["composite"]);  // as fast as a, worse
}

TEST(BenchSpeedup, LogTimeInterpolatedOnTheRenderCurve) {
  BenchResult r;
  r.layers = {"composite"};
  r.configs = {config("mid", 0.1, 21.5), config("above", 0.1, 30), config("below", 0.1, 10)};
  add_render_curve(r);
  pipeline::equal_error_speedups(r);
  // Half way from 20 to 23 dB: sqrt(1 * 2) s, over 0.1 s.
  EXPECT_NEAR(r.configs[0].speedup, 10 * std::sqrt(2.0), 1e-9);
  EXPECT_EQ(r.configs[0].speedup_bound, "");
  // Beyond the curve: a bound at its end.
  EXPECT_NEAR(r.configs[1].speedup, 20.0, 1e-9);
  EXPECT_EQ(r.configs[1].speedup_bound, ">");
  EXPECT_NEAR(r.configs[2].speedup, 10.0, 1e-9);
  EXPECT_EQ(r.configs[2].speedup_bound, "<");
}

// A calibration render's time is part of what a configuration costs: the Pareto front and the
// speedup take seconds_per_frame plus it.
TEST(BenchSpeedup, TheCalibrationRendersTimeIsCounted) {
  BenchResult r;
  r.layers = {"composite"};
  r.configs = {config("a", 1.0, 22), config("b", 0.5, 19), config("c", 0.1, 21.5)};
  r.configs[1].calibration_seconds = 0.6;  // 1.1 s in all: slower than a and c, and worse
  r.configs[2].calibration_seconds = 0.1;
  pipeline::mark_pareto(r);
  EXPECT_TRUE(r.configs[0].pareto["composite"]);
  EXPECT_FALSE(r.configs[1].pareto["composite"]);
  EXPECT_TRUE(r.configs[2].pareto["composite"]);
  add_render_curve(r);
  pipeline::equal_error_speedups(r);
  EXPECT_NEAR(r.configs[2].speedup, 5 * std::sqrt(2.0), 1e-9);  // sqrt(2) s over 0.2 s
  r.configs[2].calibration_seconds = -1;  // a render without a time: not counted
  pipeline::equal_error_speedups(r);
  EXPECT_NEAR(r.configs[2].speedup, 10 * std::sqrt(2.0), 1e-9);
}

// bench reads the calibration render's time from its header (room_poles' frame 1: 01:21.59)
// and spreads it over the frames; the speedup counts it. (The render curve is the static
// camera's frames, another shot: a finite PSNR, a curve of one point.)
TEST(BenchRun, CalibrationRenderTimeFromItsHeader) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const std::string cal = test::kRoomPoles + "/frame_0001.exr";
  const auto b = test::run_hbil(
      "bench " + test::q(in) + " -o " + test::q(dir / "bench") + " --frames 1-2 --ref " +
          test::q("composite=" + in + ":Combined") + " --render " +
          test::q(test::kSourceDir + "/samples/room_static/frame_####.exr") +
          " --set calibration=" + test::q(cal),
      dir.path());
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_TRUE(contains(b.out, "+cal s")) << b.out;
  std::ifstream jf(dir / "bench/bench.json");
  const nlohmann::json j = nlohmann::json::parse(jf);
  const nlohmann::json& c = j["configurations"][0];
  const double cal_s = c["calibration_render_seconds_per_frame"].get<double>();
  EXPECT_NEAR(cal_s, (81.59 + 0.005) / 2, 1e-9);
  // One render: the speedup is bound at its time per frame.
  const double render_s = j["renders"][0]["seconds_per_frame"].get<double>();
  EXPECT_TRUE(c.contains("equal_error_speedup_bound"));
  EXPECT_NEAR(
      c["equal_error_speedup"].get<double>() * (c["seconds_per_frame"].get<double>() + cal_s),
      render_s, 1e-9 * render_s);
}

// The bench's errors are `hbil compare`'s: ao (32-bit in the file) to 1e-9 dB; composite
// (half in the file) within 0.01 dB, on R, G, B.
TEST(BenchRun, ErrorsEqualCompareOnRunOutput) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const auto b = test::run_hbil(
      "bench " + test::q(in) + " -o " + test::q(dir / "bench") + " --frames 1-2 --ref " +
          test::q("ao=" + in + ":AO") + " --ref " + test::q("composite=" + in + ":Combined") +
          " --preset " + test::q(test::kSourceDir + "/presets/fast.json") +
          " --sweep slices=1,2 -q",
      dir.path());
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_TRUE(contains(b.out, "fast slices=1")) << b.out;
  std::ifstream jf(dir / "bench/bench.json");
  const nlohmann::json j = nlohmann::json::parse(jf);
  ASSERT_EQ(j["configurations"].size(), 2u);
  EXPECT_EQ(j["frames"], nlohmann::json({1, 2}));
  for (const auto* f : {"bench.csv", "chart.svg", "chart.png"})
    EXPECT_TRUE(fs::exists(dir / ("bench/" + std::string(f)))) << f;
  auto png = OIIO::ImageInput::open(dir / "bench/chart.png");
  ASSERT_TRUE(png);
  EXPECT_EQ(png->spec().width, 2 * 560);  // a panel per layer
  std::ifstream sf(dir / "bench/chart.svg");
  const std::string svg((std::istreambuf_iterator<char>(sf)), {});
  EXPECT_TRUE(contains(svg, "fast slices=2"));

  const nlohmann::json& c = j["configurations"][1];
  ASSERT_EQ(c["name"], "fast slices=2");
  const auto run =
      test::run_hbil("run " + test::q(in) + " --frames 1-2 -o " + test::q(dir / "out/f_####.exr") +
                         " --preset " + test::q(test::kSourceDir + "/presets/fast.json") +
                         " --set slices=2 --set 'outputs=[\"ao\",\"composite\"]' "
                         "--no-display -q",
                     dir.path());
  ASSERT_EQ(run.code, 0) << run.err;
  auto compare = [&](const std::string& layer, const std::string& ref) {
    const auto r = test::run_hbil("compare " + test::q(dir / "out/f_####.exr") + " " + test::q(in) +
                                      " --layer " + layer + " --ref-layer " + ref + " --json",
                                  dir.path());
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  };
  const nlohmann::json ao = compare("ao", "AO");
  EXPECT_NEAR(c["layers"]["ao"]["psnr"].get<double>(), ao["overall"]["psnr"].get<double>(), 1e-9);
  EXPECT_EQ(c["layers"]["ao"]["pixels"], ao["overall"]["pixels"]);
  // compare averages in alpha; R, G, B alone from its channel table.
  const nlohmann::json comp = compare("composite", "Combined");
  double sq = 0;
  size_t n = 0;
  for (const auto& ch : comp["channels"])
    if (!contains(ch["test"].get<std::string>(), ".A")) {
      const double rmse = ch["rmse"].get<double>();
      sq += rmse * rmse * ch["pixels"].get<double>();
      n += ch["pixels"].get<size_t>();
    }
  const double rgb_psnr = -10 * std::log10(sq / double(n));
  EXPECT_NEAR(c["layers"]["composite"]["psnr"].get<double>(), rgb_psnr, 0.01);
  EXPECT_GT(c["seconds_per_frame"].get<double>(), 0);
}

// On the static camera (identical Cycles frames): a tagged second reference for the composite
// gives the same figures; single frames do not change at all, the chain does (it converges),
// the reference not at all. On the cut sample the chain reports the cut at frame 4.
TEST(BenchRun, ChangeTaggedReferencesAndCuts) {
  test::TempDir dir(test::test_name());
  const std::string st = test::kSourceDir + "/samples/room_static/frame_####.exr";
  pipeline::BenchSettings s;
  s.shot = st;
  s.frames = "1-3";
  Params single;
  single.temporal = false;
  s.configs = {{"single", single}, {"temporal", Params{}}};
  s.refs = {pipeline::parse_bench_reference("composite=" + st + ":Combined"),
            pipeline::parse_bench_reference("composite@again=" + st + ":Combined"),
            pipeline::parse_bench_reference("indirect=" + st + ":DiffCol*DiffInd")};
  const BenchResult r = pipeline::run_bench(s);
  EXPECT_EQ(r.layers, (std::vector<std::string>{"composite", "composite@again", "indirect"}));
  EXPECT_EQ(r.composite, "composite");
  for (const ConfigResult& c : r.configs) {
    EXPECT_EQ(c.errors.at("composite").sum_sq, c.errors.at("composite@again").sum_sq) << c.name;
    EXPECT_EQ(c.psnr.at("indirect").size(), 3u);
    EXPECT_EQ(c.reference_change.at("composite"), 0.0) << c.name;
    EXPECT_TRUE(c.cuts.empty()) << c.name;
  }
  EXPECT_EQ(r.configs[0].change.at("composite"), 0.0);
  EXPECT_GT(r.configs[1].change.at("composite"), 1e-4);
  EXPECT_LT(r.configs[1].change.at("composite"), 0.05);

  const std::string cut = test::kSourceDir + "/samples/room_cut/frame_####.exr";
  s.shot = cut;
  s.frames = "3-5";
  s.configs = {{"temporal", Params{}}};
  s.refs = {pipeline::parse_bench_reference("indirect=" + cut + ":DiffCol*DiffInd")};
  const BenchResult rc = pipeline::run_bench(s);
  ASSERT_EQ(rc.configs[0].cuts.size(), 1u);
  EXPECT_EQ(rc.configs[0].cuts[0].first, 4);
  EXPECT_TRUE(contains(rc.configs[0].cuts[0].second, "camera moved"));
  EXPECT_GT(rc.configs[0].reference_change.at("indirect"), 0.1);  // a cut changes the image
}

// A configuration with an environment gets its far field in the composite, as `hbil run`
// gives it, though bench computes only the layers judged (no farfield layer).
TEST(BenchRun, EnvironmentReachesTheComposite) {
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  pipeline::BenchSettings s;
  s.shot = in;
  s.frames = "1";
  Params lit;
  lit.environment = "rgb:0.5,0.5,0.5";
  s.configs = {{"none", Params{}}, {"lit", lit}};
  s.refs = {pipeline::parse_bench_reference("composite=" + in + ":Combined")};
  const BenchResult r = pipeline::run_bench(s);
  const ErrorStats &a = r.configs[0].errors.at("composite"),
                   &b = r.configs[1].errors.at("composite");
  EXPECT_EQ(a.count, b.count);
  // The far field adds light: the composite's sum grows.
  EXPECT_GT(b.test_sum, a.test_sum * 1.001);
}

TEST(BenchRun, RenderWithoutCompositeReferenceIsUsageError) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const auto b =
      test::run_hbil("bench " + test::q(in) + " -o " + test::q(dir / "b") + " --frames 1 --ref " +
                         test::q("ao=" + in + ":AO") + " --render " + test::q(in) + " -q",
                     dir.path());
  EXPECT_EQ(b.code, int(Exit::usage)) << b.err;
  EXPECT_TRUE(contains(b.err, "--ref composite")) << b.err;
  EXPECT_FALSE(fs::exists(dir / "b"));
}

}  // namespace
}  // namespace hbil

namespace hbil {
namespace {

// `hbil tune` on one sample frame: the preset it writes loads, records what it was tuned on,
// and is within the tolerance of the base configuration or better; with a budget nothing
// meets, it says so and keeps the fastest configuration it found.
TEST(Tune, WritesAPresetNoWorseThanTheBase) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const std::string refs = " --frames 1 --ref " + test::q("ao=" + in + ":AO") + " --ref " +
                           test::q("composite=" + in + ":Combined");
  const auto t =
      test::run_hbil("tune " + test::q(in) + refs + " -o " + test::q(dir / "t.json"), dir.path());
  ASSERT_EQ(t.code, 0) << t.err;
  std::ifstream f(dir / "t.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_NO_THROW(params_from_json(j, "tuned preset"));
  EXPECT_EQ(j["tuned"]["layer"], "composite");
  EXPECT_EQ(j["tuned"]["frames"], "1");
  EXPECT_EQ(j["tuned"]["references"].size(), 2u);
  EXPECT_GT(j["tuned"]["configurations_measured"].get<int>(), 10);
  // The base: bench with the defaults, on the same frame.
  const auto b = test::run_hbil("bench " + test::q(in) + refs + " -o " + test::q(dir / "b") + " -q",
                                dir.path());
  ASSERT_EQ(b.code, 0) << b.err;
  std::ifstream bf(dir / "b/bench.json");
  const nlohmann::json bj = nlohmann::json::parse(bf);
  const double base = bj["configurations"][0]["layers"]["composite"]["psnr"].get<double>();
  EXPECT_GE(j["tuned"]["errors"]["composite"]["psnr"].get<double>(), base - 0.1 - 1e-9);

  const auto none = test::run_hbil(
      "tune " + test::q(in) + refs + " --budget 1e-6 -q -o " + test::q(dir / "n.json"), dir.path());
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_TRUE(contains(none.out, "none was")) << none.out;

  // A calibration render's time counts against the budget: frame 1's header says 01:21.59,
  // more than 10 s a frame, whatever hbil's own time.
  const auto cal =
      test::run_hbil("tune " + test::q(in) + refs + " --keys slices --budget 10" +
                         " --set calibration=" + test::q(test::kRoomPoles + "/frame_0001.exr") +
                         " -q -o " + test::q(dir / "c.json"),
                     dir.path());
  ASSERT_EQ(cal.code, 0) << cal.err;
  EXPECT_TRUE(contains(cal.out, "none was")) << cal.out;
  std::ifstream cf(dir / "c.json");
  EXPECT_GT(nlohmann::json::parse(cf)["tuned"]["seconds_per_frame"].get<double>(), 81.59);
}

// With a budget, a configuration whose one timed run lands within retime_band of it is timed
// three more times (the median decides whether it fits); far from it, or with no band, once.
TEST(Tune, RetimesOnlyNearTheBudget) {
  pipeline::TuneSettings t;
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  t.bench.shot = in;
  t.bench.frames = "1";
  t.bench.configs = {{"default", Params{}}};
  t.bench.refs = {pipeline::parse_bench_reference("ao=" + in + ":AO")};
  t.keys = {"slices"};
  t.budget = 1000;  // seconds a frame: every configuration fits, far below it
  auto runs = [&](double band) {
    t.retime_band = band;
    std::vector<int> r;
    for (const pipeline::TuneStep& s : pipeline::run_tune(t).steps) r.push_back(s.runs);
    return r;
  };
  // base (slices "auto"), slices=1, slices=2, slices=4
  EXPECT_EQ(runs(0.2), (std::vector<int>{1, 1, 1, 1}));
  EXPECT_EQ(runs(0), (std::vector<int>{1, 1, 1, 1}));
  EXPECT_EQ(runs(2), (std::vector<int>{3, 3, 3, 3}));  // every time within 2000 s of the budget
}

// --keys: only those keys are tried (every step changes one of them), the preset says so; a
// key tune does not search is a usage error and writes nothing.
TEST(Tune, KeysLimitTheSearch) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const std::string refs = " --frames 1 --ref " + test::q("ao=" + in + ":AO");
  const auto t = test::run_hbil(
      "tune " + test::q(in) + refs + " --keys slices,steps -o " + test::q(dir / "t.json"),
      dir.path());
  ASSERT_EQ(t.code, 0) << t.err;
  size_t tried = 0;
  std::istringstream lines(t.err);
  for (std::string line; std::getline(lines, line);)
    if (contains(line, "tune: ")) {
      ++tried;
      EXPECT_TRUE(contains(line, "tune: base") || contains(line, "tune: slices=") ||
                  contains(line, "tune: steps="))
          << line;
    }
  EXPECT_GE(tried, 5u);  // the base, 2 other slices, 3 other steps at least
  std::ifstream f(dir / "t.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["tuned"]["keys"], nlohmann::json({"slices", "steps"}));
  const auto bad = test::run_hbil(
      "tune " + test::q(in) + refs + " --keys radius -q -o " + test::q(dir / "b.json"), dir.path());
  EXPECT_EQ(bad.code, int(Exit::usage)) << bad.err;
  EXPECT_TRUE(contains(bad.err, "--keys radius: not a key tune searches")) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "b.json"));
}

// unseen_radiance and unseen_carry are tune's keys: on room_poles, whose unseen walls and
// ceiling light it (README "Light from what the frame does not show": +2.8 dB of composite
// over the move with unseen_carry), the composite's reference keeps "auto" and chooses
// unseen_carry; an ao objective, which they cannot change, does not try them.
TEST(Tune, ChoosesUnseenRadianceWhereTheReferenceShowsIt) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  // tune on frame 1 with one reference, over the two keys: its stderr and the preset written.
  auto tune = [&](const std::string& ref, const std::string& out) {
    const auto r =
        test::run_hbil("tune " + test::q(in) + " --frames 1 --ref " + test::q(ref) +
                           " --keys unseen_radiance,unseen_carry -o " + test::q(dir / out),
                       dir.path());
    EXPECT_EQ(r.code, 0) << r.err;
    std::ifstream f(dir / out);
    return std::pair{r.err, nlohmann::json::parse(f, nullptr, false)};
  };
  const auto [err, j] = tune("composite=" + in + ":Combined", "t.json");
  EXPECT_TRUE(contains(err, "tune: unseen_radiance=0")) << err;
  EXPECT_EQ(j["unseen_radiance"], "auto");
  EXPECT_EQ(j["unseen_carry"], true);
  const auto [ao_err, aj] = tune("ao=" + in + ":AO", "a.json");
  EXPECT_FALSE(contains(ao_err, "tune: unseen_")) << ao_err;
  EXPECT_EQ(aj["unseen_radiance"], "auto");
  EXPECT_EQ(aj["unseen_carry"], "auto");  // not tried: the default kept
}

TEST(Tune, UnknownObjectiveLayerIsUsageError) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const auto t =
      test::run_hbil("tune " + test::q(in) + " --frames 1 --ref " + test::q("ao=" + in + ":AO") +
                         " --layer composite -q -o " + test::q(dir / "new/t.json"),
                     dir.path());
  EXPECT_EQ(t.code, int(Exit::usage)) << t.err;
  EXPECT_TRUE(contains(t.err, "--layer composite: no --ref for it")) << t.err;
  EXPECT_FALSE(fs::exists(dir / "new")) << "no file, and no folder, from a failed tune";
}

}  // namespace
}  // namespace hbil

namespace hbil {
namespace {

// --stability on three sample frames: single frames repeat their samples (flicker exactly
// 0); the cut from the shot's frame 8 back to frame 1 is found by the rejected history and its
// first frame is the uncut run's (0 frames to recover); with every cut threshold off it is
// not; every non-finite input is refused.
TEST(BenchStability, FiguresOnTheSample) {
  test::TempDir dir(test::test_name());
  const std::string in = test::kRoomPoles + "/frame_####.exr";
  const auto b = test::run_hbil(
      "bench " + test::q(in) + " -o " + test::q(dir / "s") + " --frames 1-3 --ref " +
          test::q("composite=" + in + ":Combined") + " --stability -q --sweep temporal=true,false" +
          " --sweep cut_rejected=0.6,1 --set cut_camera_angle=180 --set cut_camera_jump=1000",
      dir.path());
  ASSERT_EQ(b.code, 0) << b.err;
  std::ifstream jf(dir / "s/bench.json");
  const nlohmann::json j = nlohmann::json::parse(jf);
  ASSERT_EQ(j["configurations"].size(), 4u);
  std::map<std::string, nlohmann::json> st;
  for (const auto& c : j["configurations"]) st[c["name"]] = c["stability"];
  const auto& chain = st["default temporal=true cut_rejected=0.6"];
  const auto& blind = st["default temporal=true cut_rejected=1"];
  const auto& single = st["default temporal=false cut_rejected=0.6"];
  EXPECT_EQ(chain["layer"], "composite");
  EXPECT_GT(chain["flicker"].get<double>(), 0);
  EXPECT_EQ(single["flicker"].get<double>(), 0);
  EXPECT_TRUE(chain["cut_detected"].get<bool>());
  EXPECT_EQ(chain["cut_recovery_frames"], 0);
  EXPECT_FALSE(blind["cut_detected"].get<bool>());
  EXPECT_NE(blind["cut_recovery_frames"], 0);
  for (const auto& [name, f] : st) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(f["robust"].get<bool>());
    EXPECT_TRUE(f["zero_normals_finite"].get<bool>());
    EXPECT_EQ(f["non_finite_input"],
              "NaN depth: refused (exit 5), infinite depth: refused (exit 5), NaN DiffCol: "
              "refused (exit 5)");
    EXPECT_GT(f["edge_rmse"].get<double>(), 0);
    EXPECT_GT(f["thin_rmse"].get<double>(), 0);  // the sample's poles and fence
    EXPECT_GT(f["thin_share"].get<double>(), 0.01);
  }
  EXPECT_TRUE(fs::exists(dir / "s/stability.csv"));
}

}  // namespace
}  // namespace hbil
