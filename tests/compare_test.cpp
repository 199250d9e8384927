// compare_test.cpp: `hbil compare` with layer expressions (--layer, --ref-layer 'DiffCol*DiffInd'),
// run through the hbil binary.
//
// The synthetic image holds layers A, B, C (RGB), a one-channel layer M and layers computed
// from them (P = A*B, Q = A*(B+C), T = A*B+C, MA = M*A). Every value is a small dyadic
// fraction (k/8, k/16, k/32), so each product and sum is exact in float and the expected
// errors are exactly 0, whatever the order of the operations.

#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hbil/error.h"
#include "test_util.h"

namespace hbil {
namespace {

using nlohmann::json;
using test::contains;
using test::q;
using test::RunResult;
using test::TempDir;

constexpr int kW = 4, kH = 3;

// Layer values at (x, y), component c (0 R, 1 G, 2 B).
double a(int x, int y, int c) {
  return (1 + x + 4 * y + c) / 16.0;
}
double b(int x, int y, int c) {
  return (16 - x - 2 * y - c) / 32.0;
}
double c_(int x, int y, int c) {
  return (x * c + 3) / 8.0;
}
double m(int x, int y) {
  return (x + y + 1) / 4.0;
}

struct Layer {
  std::string name;
  std::vector<std::string> comps;  // in file order
  std::function<double(int, int, int)> value;
};

const std::vector<Layer>& layers() {
  static const std::vector<Layer> l = {
      {"A", {"R", "G", "B"}, a},
      // File order B G R: operands are combined by component, not by position in the file.
      {"B", {"B", "G", "R"}, b},
      {"C", {"R", "G", "B"}, c_},
      {"M", {"Y"}, [](int x, int y, int) { return m(x, y); }},
      {"V", {"X", "Y"}, [](int x, int y, int c) { return (x + y + c) / 8.0; }},
      {"P", {"R", "G", "B"}, [](int x, int y, int c) { return a(x, y, c) * b(x, y, c); }},
      {"Q",
       {"R", "G", "B"},
       [](int x, int y, int c) { return a(x, y, c) * (b(x, y, c) + c_(x, y, c)); }},
      {"T",
       {"R", "G", "B"},
       [](int x, int y, int c) { return a(x, y, c) * b(x, y, c) + c_(x, y, c); }},
      {"MA", {"R", "G", "B"}, [](int x, int y, int c) { return m(x, y) * a(x, y, c); }},
  };
  return l;
}

int component(const std::string& comp) {
  return comp == "R" || comp == "X" ? 0 : comp == "G" || comp == "Y" ? 1 : 2;
}

class Compare : public ::testing::Test {
 protected:
  void SetUp() override {
    std::vector<std::string> channels;
    std::vector<std::pair<const Layer*, int>> source;  // per channel: layer, component
    for (const auto& l : layers())
      for (const auto& comp : l.comps) {
        channels.push_back(l.name + "." + comp);
        source.emplace_back(&l, l.comps.size() == 1 ? 0 : component(comp));
      }
    test::write_exr(image, kW, kH, channels, [&](int x, int y, int ch) {
      return float(source[ch].first->value(x, y, source[ch].second));
    });
  }

  RunResult hbil(const std::string& args) { return test::run_hbil(args, dir.path()); }

  // `compare image image --layer L --ref-layer R --mask none --json`, parsed; fails the
  // test (and returns null) unless it exits 0.
  json compare(const std::string& layer, const std::string& ref_layer) {
    const RunResult r = hbil("compare " + q(image) + " " + q(image) + " --layer " + q(layer) +
                             " --ref-layer " + q(ref_layer) + " --mask none --json");
    EXPECT_EQ(r.code, 0) << layer << " vs " << ref_layer << ": " << r.err;
    if (r.code != 0) return nullptr;
    return json::parse(r.out);
  }
  double rmse(const std::string& layer, const std::string& ref_layer) {
    const json j = compare(layer, ref_layer);
    return j.is_null() ? -1 : j["overall"]["rmse"].get<double>();
  }

  TempDir dir{test::test_name()};
  const std::string image = dir / "layers.exr";
};

TEST_F(Compare, ProductOfTwoLayers) {
  const json j = compare("P", "A*B");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["overall"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(j["overall"]["psnr"], "inf");
  EXPECT_EQ(j["overall"]["pixels"].get<size_t>(), size_t(3) * kW * kH);
  EXPECT_EQ(j["layer"], "P");
  EXPECT_EQ(j["ref_layer"], "A*B");
  ASSERT_EQ(j["channels"].size(), 3u);
  EXPECT_EQ(j["channels"][0]["test"], "P.R");
  EXPECT_EQ(j["channels"][0]["reference"], "(A*B).R");
  EXPECT_EQ(j["channels"][2]["reference"], "(A*B).B");

  EXPECT_EQ(rmse("P", "B*A"), 0.0);
  EXPECT_EQ(rmse("A*B", "P"), 0.0);
  EXPECT_EQ(rmse("A*B", "B*A"), 0.0);
  // The expression is evaluated, not ignored: P against A alone differs by the known mean.
  const json ja = compare("P", "A");
  ASSERT_FALSE(ja.is_null());
  double mean = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) mean += a(x, y, c) * b(x, y, c) - a(x, y, c);
  mean /= 3 * kW * kH;
  EXPECT_NEAR(ja["overall"]["mean_error"].get<double>(), mean, 1e-12);
  EXPECT_GT(ja["overall"]["rmse"].get<double>(), 0.1);
}

TEST_F(Compare, SumsParenthesesAndPrecedence) {
  EXPECT_EQ(rmse("Q", "A*(B+C)"), 0.0);
  EXPECT_EQ(rmse("Q", "(C+B)*A"), 0.0);
  EXPECT_EQ(rmse("T", "A*B+C"), 0.0);  // * binds tighter than +
  EXPECT_EQ(rmse("T", "C+B*A"), 0.0);
  EXPECT_EQ(rmse("T", "(A*B)+C"), 0.0);
  EXPECT_EQ(rmse("T", "C+P"), 0.0);
  EXPECT_EQ(rmse("Q", " A * ( B + C ) "), 0.0);  // spaces are ignored
  EXPECT_EQ(rmse("Q", "A*B+A*C"), 0.0);          // exact here: dyadic values
  EXPECT_GT(rmse("Q", "A*B+C"), 0.05);
  EXPECT_GT(rmse("T", "A*(B+C)"), 0.05);

  // The output names the expression in its shortest form, in JSON and in the table.
  const json j = compare("Q", " ( A * ( B + C ) ) ");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["ref_layer"], "A*(B+C)");
  EXPECT_EQ(j["channels"][1]["reference"], "(A*(B+C)).G");
  const RunResult t = hbil("compare " + q(image) + " " + q(image) + " --layer Q --ref-layer " +
                           q("A*(B+C)") + " --mask none");
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_TRUE(contains(t.out, "Q.R vs (A*(B+C)).R")) << t.out;
  EXPECT_TRUE(contains(t.out, "overall")) << t.out;
}

TEST_F(Compare, OneChannelLayerIsBroadcast) {
  const json j = compare("MA", "M*A");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["overall"]["rmse"].get<double>(), 0.0);
  ASSERT_EQ(j["channels"].size(), 3u);
  EXPECT_EQ(j["channels"][1]["reference"], "(M*A).G");  // the component of the 3-channel A
  EXPECT_EQ(rmse("MA", "A*M"), 0.0);
  EXPECT_EQ(rmse("M*A+C", "C+MA"), 0.0);
  // A one-channel expression against a three-channel layer: compared with each channel.
  const json one = compare("M*M", "MA");
  ASSERT_FALSE(one.is_null());
  ASSERT_EQ(one["channels"].size(), 3u);
  EXPECT_EQ(one["channels"][0]["test"], "(M*M).Y");
}

TEST_F(Compare, PlainLayerUnchanged) {
  const json j = compare("A", "A");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["layer"], "A");
  EXPECT_EQ(j["channels"][0]["test"], "A.R");
  EXPECT_EQ(j["channels"][0]["reference"], "A.R");
  EXPECT_EQ(j["overall"]["rmse"].get<double>(), 0.0);
  // A channel named in full still works.
  EXPECT_EQ(rmse("B.G", "B.G"), 0.0);
}

TEST_F(Compare, UnknownLayerInExpression) {
  const RunResult r = hbil("compare " + q(image) + " " + q(image) + " --layer P --ref-layer " +
                           q("A*Nope") + " --mask none");
  EXPECT_EQ(r.code, int(Exit::missing_pass)) << r.err;
  EXPECT_TRUE(contains(r.err, "no layer 'Nope'")) << r.err;
  EXPECT_TRUE(contains(r.err, "--ref-layer 'A*Nope'")) << r.err;

  const RunResult t = hbil("compare " + q(image) + " " + q(image) + " --layer " + q("(Gone+A)*B") +
                           " --ref-layer P --mask none");
  EXPECT_EQ(t.code, int(Exit::missing_pass)) << t.err;
  EXPECT_TRUE(contains(t.err, "no layer 'Gone'")) << t.err;
}

TEST_F(Compare, MismatchedChannelCounts) {
  const RunResult r = hbil("compare " + q(image) + " " + q(image) + " --layer P --ref-layer " +
                           q("A*V") + " --mask none");
  EXPECT_EQ(r.code, int(Exit::usage)) << r.err;
  EXPECT_TRUE(contains(r.err, "'A' has 3 channels but 'V' has 2")) << r.err;
}

TEST_F(Compare, MalformedExpressionIsUsageError) {
  for (const std::string e :
       {"A*", "*A", "A+*B", "(A*B", "A*B)", "()", "A**B", "A*(B+)", " ", "A+(", ")"}) {
    const RunResult r = hbil("compare " + q(image) + " " + q(image) + " --layer P --ref-layer " +
                             q(e) + " --mask none");
    EXPECT_EQ(r.code, int(Exit::usage)) << "'" << e << "': " << r.err;
    EXPECT_TRUE(contains(r.err, "--ref-layer '" + e + "'")) << r.err;
  }
  // Checked before any file is read: a usage error, not a missing file.
  const RunResult r = hbil("compare " + q(dir / "none.exr") + " " + q(dir / "none.exr") +
                           " --layer " + q("A+") + " --mask none");
  EXPECT_EQ(r.code, int(Exit::usage)) << r.err;
  EXPECT_TRUE(contains(r.err, "--layer 'A+'")) << r.err;
}

// The Blender sample: DiffCol and DiffInd found through the ViewLayer prefix, 8 frames.
TEST(CompareBlender, IndirectReferenceProduct) {
  const std::string frames = test::kRoomPoles + "/bounce1/frame_####.exr";
  if (!std::filesystem::exists(test::kRoomPoles + "/bounce1/frame_0001.exr"))
    GTEST_SKIP() << "samples/room_poles/bounce1 is absent";
  TempDir dir(test::test_name());
  auto run = [&](const std::string& layer, const std::string& ref_layer) {
    const RunResult r = test::run_hbil("compare " + q(frames) + " " + q(frames) + " --layer " +
                                           q(layer) + " --ref-layer " + q(ref_layer) + " --json",
                                       dir.path());
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? json::parse(r.out) : json(nullptr);
  };

  const json lone = run("DiffInd", "DiffInd*DiffCol");
  ASSERT_FALSE(lone.is_null());
  EXPECT_EQ(lone["frames"].size(), 8u);
  EXPECT_EQ(lone["mask"], "ViewLayer.Depth.Z < background");
  EXPECT_GT(lone["overall"]["rmse"].get<double>(), 0.0);
  ASSERT_EQ(lone["channels"].size(), 3u);
  EXPECT_EQ(lone["channels"][0]["test"], "ViewLayer.DiffInd.R");
  EXPECT_EQ(lone["channels"][0]["reference"], "(DiffInd*DiffCol).R");

  const json same = run("DiffCol*DiffInd", "DiffInd*DiffCol");
  ASSERT_FALSE(same.is_null());
  EXPECT_EQ(same["overall"]["rmse"].get<double>(), 0.0);
  EXPECT_EQ(same["overall"]["pixels"], lone["overall"]["pixels"]);

  // Distributing the product rounds differently in float: equal to float precision only.
  // Values are below ~10, so 1e-5 is some 100 float ulps.
  const json dist = run("DiffCol*(DiffDir+DiffInd)", "DiffCol*DiffDir+DiffCol*DiffInd");
  ASSERT_FALSE(dist.is_null());
  EXPECT_LT(dist["overall"]["rmse"].get<double>(), 1e-5);
}

}  // namespace
}  // namespace hbil
