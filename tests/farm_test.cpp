// farm_test.cpp: `hbil farm`: the pre-roll that keeps seams under
// the tolerance, the memory a task asks for, chunks that follow cuts, a chunk's run, the
// check of a shot and the Slurm scripts. The job array on a real Slurm is tests/slurm/run.sh.
#include "pipeline/farm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hbil/error.h"
#include "test_util.h"

namespace hbil {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::q;

// The pre-roll follows the parameters' temporal memory: longer history, longer pre-roll; none
// without a temporal chain. The fit (farm.cpp) gives 36 frames for the default 0.9 with
// feedback: cold difference 0.02 fading by 0.92 a frame, 0.02 x 0.92^36 = 0.0010.
TEST(FarmPreroll, FollowsTheTemporalMemory) {
  Params p;
  p.temporal = true;
  p.feedback = true;
  p.history_weight = 0.9;
  std::string why;
  EXPECT_EQ(pipeline::seam_preroll(p, &why), 36);
  EXPECT_TRUE(contains(why, "0.92")) << why;
  EXPECT_LE(0.02 * std::pow(0.92, 36), pipeline::kSeamTolerance * 1.001);
  EXPECT_GT(0.02 * std::pow(0.92, 35), pipeline::kSeamTolerance);
  p.history_weight = 0.7;
  const int shorter = pipeline::seam_preroll(p);
  EXPECT_LT(shorter, 36);
  p.feedback = false;
  EXPECT_LT(pipeline::seam_preroll(p), shorter);  // 0.02 x 0.7^9 < 0.001
  EXPECT_EQ(pipeline::seam_preroll(p), 9);
  p.temporal = false;
  EXPECT_EQ(pipeline::seam_preroll(p, &why), 0);
  EXPECT_TRUE(contains(why, "no temporal chain")) << why;
}

// With history_window W the memory is finite: 2W − 2 frames at most, 3 more for the light
// fed back; a chunk that starts where a chain restarts next needs W − 1 + 3.
TEST(FarmPreroll, AFiniteWindowNeedsItsMemory) {
  Params p;
  p.history_window = 6;
  std::string why;
  EXPECT_EQ(pipeline::seam_preroll(p, &why), 13);
  EXPECT_TRUE(contains(why, "history_window 6")) << why;
  EXPECT_EQ(pipeline::window_preroll(p, 47, 1), 8);  // (47 + 1) mod 12 = 0
  EXPECT_EQ(pipeline::window_preroll(p, 46, 1), 13);
  EXPECT_EQ(pipeline::window_preroll(p, 46, 2), 8);  // 10 frame numbers at a step of 2
  p.temporal = false;
  EXPECT_EQ(pipeline::window_preroll(p, 47, 1), 0);
}

// From the peaks bench/speed.sh measured on room_poles (155 MB at 256x144, 839 MB at
// 1920x1080 with overlap, 1098 MB at 3840x2160 without; README "Speed" gives another run's
// 831 and 1093 MB), each within 2 %.
TEST(FarmMemory, FitsTheMeasuredPeaks) {
  EXPECT_NEAR(pipeline::run_memory_mb(256, 144), 155, 155 * 0.02);
  EXPECT_NEAR(pipeline::run_memory_mb(1920, 1080), 839, 839 * 0.02);
  EXPECT_NEAR(pipeline::run_memory_mb(3840, 2160), 1098, 1098 * 0.02);
}

class Farm : public ::testing::Test {
 protected:
  test::RunResult hbil(const std::string& args) { return test::run_hbil(args, dir.path()); }
  nlohmann::json plan_json() const {
    return nlohmann::json::parse(test::read_text(dir / "plan.json"));
  }
  test::TempDir dir{test::test_name()};
};

// room_cut cuts at frame 4 (the camera jumps): that frame starts a chunk with no pre-roll;
// the other chunks pre-roll back to the shot's start or to the cut, never across it.
TEST_F(Farm, PlanFollowsTheCuts) {
  const std::string shot = test::kSourceDir + "/samples/room_cut/frame_####.exr";
  const auto r = hbil("farm plan " + q(shot) + " -o " + q(dir / "plan.json") + " --chunk 2 -- -o " +
                      q(dir / "out/f_####.exr"));
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = plan_json();
  EXPECT_EQ(j["cuts"], nlohmann::json::array({4}));
  EXPECT_EQ(j["preroll"], 36);
  EXPECT_EQ(j["resolution"], nlohmann::json::array({256, 144}));
  const auto& c = j["chunks"];
  ASSERT_EQ(c.size(), 4u) << j.dump(2);
  const std::vector<std::string> frames = {"1-2", "3", "4-5", "6"};
  const std::vector<int> preroll = {0, 2, 0, 2};
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(c[i]["frames"], frames[i]) << i;
    EXPECT_EQ(c[i]["preroll"], preroll[i]) << i;
  }
  EXPECT_EQ(c[0]["starts"], "shot");
  EXPECT_EQ(c[1]["starts"], "chunk");
  EXPECT_TRUE(contains(c[2]["starts"].get<std::string>(), "cut: camera")) << c[2]["starts"];
  EXPECT_TRUE(contains(r.out, "chunk 2: frames 4-5, pre-roll 0 (cut: camera")) << r.out;

  // A given cut starts a chunk too; --preroll takes a count.
  ASSERT_EQ(hbil("farm plan " + q(shot) + " -o " + q(dir / "plan.json") +
                 " --chunk 3 --cut-frames 6 --preroll 1 -q -- -o " + q(dir / "out/f_####.exr"))
                .code,
            0);
  const nlohmann::json k = plan_json();
  EXPECT_EQ(k["cuts"], nlohmann::json::array({4, 6}));
  ASSERT_EQ(k["chunks"].size(), 3u) << k.dump(2);
  EXPECT_EQ(k["chunks"][2]["frames"], "6");
  EXPECT_EQ(k["chunks"][2]["starts"], "cut: given");
  EXPECT_EQ(k["chunks"][2]["preroll"], 0);
}

// With history_window 2 (restarts every 4 frames) and --chunk 3, chunks start within 2
// frames of every third, at 3 and 7, where a chain restarts next: each needs 1 + 3 frames of
// pre-roll, the first of them only 2 (the shot's start).
TEST_F(Farm, AFiniteWindowPlacesTheChunksWhereTheyNeedLeast) {
  const std::string shot = test::kRoomPoles + "/frame_####.exr";
  const auto r = hbil("farm plan " + q(shot) + " -o " + q(dir / "plan.json") +
                      " --chunk 3 -q -- --set history_window=2 -o " + q(dir / "out/f_####.exr"));
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = plan_json();
  const auto& c = j["chunks"];
  ASSERT_EQ(c.size(), 3u) << j.dump(2);
  const std::vector<std::string> frames = {"1-2", "3-6", "7-8"};
  const std::vector<int> preroll = {0, 2, 4};
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(c[i]["frames"], frames[i]) << i;
    EXPECT_EQ(c[i]["preroll"], preroll[i]) << i;
  }
  EXPECT_EQ(j["preroll"], 5);
}

TEST_F(Farm, PlanRefusesWhatItCannotPlan) {
  const std::string shot = q(test::kRoomPoles + "/frame_####.exr");
  const std::string plan = " -o " + q(dir / "plan.json");
  const std::string out = " -o " + q(dir / "out/f_####.exr");
  struct Case {
    std::string args;
    Exit code;
    std::string needle;
  };
  for (const Case& c : std::vector<Case>{
           {plan + " --", Exit::usage, "-o"},
           {plan + " --" + out + " --frames 1-2", Exit::usage, "--frames is set by the plan"},
           {plan + " --" + out + " --threads 2", Exit::usage, "--threads is set by the plan"},
           {plan + " --chunk 0 --" + out, Exit::usage, "--chunk"},
           {plan + " --preroll soon --" + out, Exit::usage, "--preroll soon"},
           {plan + " --" + out + " --set nonsense=1", Exit::preset, "nonsense"},
           {plan + " --frames 1-9 --" + out, Exit::input, "frame_0009.exr"}}) {
    const auto r = hbil("farm plan " + shot + c.args);
    EXPECT_EQ(r.code, int(c.code)) << c.args << ": " << r.err;
    EXPECT_TRUE(contains(r.err, c.needle)) << c.args << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "plan.json")) << c.args;
  }
}

// Each chunk run as a task would run it gives, with the planned pre-roll reaching back to the
// shot's start, the whole run's bytes; the check names a chunk with a frame missing (exit 9)
// and the chunk to run again, and running it again completes the shot.
TEST_F(Farm, ChunksRunAndCheckedMakeTheWholeRun) {
  const std::string shot = test::kRoomPoles + "/frame_####.exr";
  ASSERT_EQ(hbil("run " + q(shot) + " -o " + q(dir / "whole/f_####.exr") + " -q").code, 0);
  ASSERT_EQ(hbil("farm plan " + q(shot) + " -o " + q(dir / "plan.json") + " --chunk 3 -q -- -o " +
                 q(dir / "out/f_####.exr"))
                .code,
            0);
  const auto before = hbil("farm check " + q(dir / "plan.json"));
  EXPECT_EQ(before.code, int(Exit::incomplete)) << before.err;
  EXPECT_TRUE(contains(before.out, "chunk 0 (frames 1-3): 3 frames not done")) << before.out;
  EXPECT_TRUE(contains(before.out, "incomplete: 8 of 8 frames not done, in chunks 0,1,2"))
      << before.out;
  for (int c = 0; c < 3; ++c) {
    const auto r = hbil("farm run " + q(dir / "plan.json") + " --chunk " + std::to_string(c) +
                        " --threads 1 --log-json " + q(dir / "log.jsonl"));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const auto done = hbil("farm check " + q(dir / "plan.json"));
  EXPECT_EQ(done.code, 0) << done.out << done.err;
  EXPECT_TRUE(contains(done.out, "complete: 8 frames in 3 chunks")) << done.out;
  for (int f = 1; f <= 8; ++f)
    for (const char* ext : {".exr", ".png"}) {
      const std::string name = "f_000" + std::to_string(f) + ext;
      EXPECT_EQ(test::read_text(dir / ("out/" + name)), test::read_text(dir / ("whole/" + name)))
          << name << " differs from the whole run's";
    }
  EXPECT_EQ(test::files_containing(dir.path(), "log.jsonl").size(), 1u);

  fs::remove(dir / "out/f_0005.png");
  const auto missing = hbil("farm check " + q(dir / "plan.json") + " --sbatch job.sbatch");
  EXPECT_EQ(missing.code, int(Exit::incomplete));
  EXPECT_TRUE(contains(missing.out, "chunk 1 (frames 4-6): 1 frame not done, the first: " +
                                        (dir / "out/f_0005.png") + " is missing"))
      << missing.out;
  EXPECT_TRUE(contains(missing.out, "submit again: sbatch --array=1 job.sbatch")) << missing.out;
  ASSERT_EQ(hbil("farm run " + q(dir / "plan.json") + " --chunk 1").code, 0);
  EXPECT_EQ(hbil("farm check " + q(dir / "plan.json")).code, 0);
  EXPECT_EQ(test::read_text(dir / "out/f_0005.png"), test::read_text(dir / "whole/f_0005.png"));

  const auto bad = hbil("farm run " + q(dir / "plan.json") + " --chunk 3");
  EXPECT_EQ(bad.code, int(Exit::usage));
  EXPECT_TRUE(contains(bad.err, "chunks 0-2")) << bad.err;
  // Plans that are not plans: each exit 3 naming the file, none a crash.
  nlohmann::json j = plan_json();
  j["chunks"][1]["preroll"] = 2000000000;
  nlohmann::json k = plan_json();
  k["chunks"][0]["frames"] = "1-x";
  for (const std::string& text : {std::string("{\"chunks\": []}"), std::string("[1, 2"),
                                  std::string("{}"), j.dump(), k.dump()}) {
    test::write_text(dir / "broken.json", text);
    for (const std::string& cmd :
         {"farm check ", "farm run --chunk 0 ", "farm slurm -o x.sbatch "}) {
      const auto broken = hbil(cmd + q(dir / "broken.json"));
      EXPECT_EQ(broken.code, int(Exit::input)) << cmd << text << broken.err;
      EXPECT_TRUE(contains(broken.err, dir / "broken.json")) << broken.err;
    }
  }
}

// The job array: one task per chunk, cores given to run as threads, memory from the plan, a
// log per task; the check beside it runs `farm check`.
TEST_F(Farm, SlurmScriptsRunEachChunkAndTheCheck) {
  const std::string shot = test::kRoomPoles + "/frame_####.exr";
  ASSERT_EQ(hbil("farm plan " + q(shot) + " -o " + q(dir / "plan.json") + " --chunk 3 -q -- -o " +
                 q(dir / "out/f_####.exr"))
                .code,
            0);
  const auto r = hbil("farm slurm " + q(dir / "plan.json") + " -o " + q(dir / "job.sbatch") +
                      " --cpus-per-task 4 --sbatch-option=--partition=post --hbil /opt/hbil");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string job = test::read_text(dir / "job.sbatch");
  for (const std::string& line :
       {std::string("#SBATCH --array=0-2\n"), std::string("#SBATCH --cpus-per-task=4\n"),
        std::string("#SBATCH --mem=512M\n"), std::string("#SBATCH --partition=post\n"),
        "#SBATCH --chdir=" + fs::current_path().string() + "\n",  // where the plan was made
        "#SBATCH --output=" + (dir / "logs") + "/hbil-room_poles-%A_%a.out\n",
        "exec /opt/hbil farm run " + (dir / "plan.json") +
            " --chunk \"$task\" --threads \"${SLURM_CPUS_PER_TASK:-4}\" --log-json " +
            (dir / "logs") + "/chunk-\"$task\".jsonl\n"})
    EXPECT_TRUE(contains(job, line)) << "job.sbatch lacks " << line << job;
  const std::string check = test::read_text(dir / "job.check.sbatch");
  EXPECT_TRUE(contains(check, "exec /opt/hbil farm check " + (dir / "plan.json") + " --sbatch " +
                                  (dir / "job.sbatch") + "\n"))
      << check;
  EXPECT_TRUE(fs::is_directory(dir / "logs"));
  EXPECT_TRUE((fs::status(dir / "job.sbatch").permissions() & fs::perms::owner_exec) !=
              fs::perms::none);
}

}  // namespace
}  // namespace hbil
