// sequence_test.cpp: frame patterns, existing frames on disk, frame lists (--frames), frame
// numbers in file names.
#include "io/sequence.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "hbil/error.h"

namespace hbil::io {
namespace {

namespace fs = std::filesystem;

// A fresh temporary directory, removed with everything in it at scope exit.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(fs::temp_directory_path() /
              ("hbil_sequence_test_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string str() const { return path_.string(); }
  void touch(const std::string& name) const { std::ofstream(path_ / name).put('x'); }

 private:
  fs::path path_;
};

void expect_usage_error(const std::string& pattern, const std::string& needle) {
  try {
    FramePattern p(pattern);
    ADD_FAILURE() << "no error for \"" << pattern << "\"";
  } catch (const Error& e) {
    EXPECT_EQ(int(e.code()), int(Exit::usage)) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "\"" << e.what() << "\" lacks \"" << needle << "\"";
  }
}

TEST(FramePattern, HashesPadToTheirCount) {
  const FramePattern p("dir/frame_####.exr");
  EXPECT_TRUE(p.is_sequence());
  EXPECT_EQ(p.text(), "dir/frame_####.exr");
  EXPECT_EQ(p.pad(), 4);
  EXPECT_EQ(p.path(1), "dir/frame_0001.exr");
  EXPECT_EQ(p.path(123), "dir/frame_0123.exr");
  EXPECT_EQ(p.path(10000), "dir/frame_10000.exr");  // more digits when needed (Blender)
  EXPECT_EQ(p.path(-3), "dir/frame_-003.exr");      // printf("%04d", -3)
  EXPECT_EQ(FramePattern("f#.exr").path(42), "f42.exr");
}

TEST(FramePattern, AtSignsPadToTheirCount) {
  EXPECT_EQ(FramePattern("f_@@@@.exr").path(7), "f_0007.exr");
  EXPECT_EQ(FramePattern("f_@@@.exr").pad(), 3);
  EXPECT_EQ(FramePattern("f_@.exr").path(42), "f_42.exr");
  EXPECT_EQ(FramePattern("f_@@@@.exr").path(-2), "f_-002.exr");
  expect_usage_error("f_##@@.exr", "more than one");
}

TEST(FramePattern, PrintfStyle) {
  EXPECT_EQ(FramePattern("frame_%04d.exr").path(7), "frame_0007.exr");
  EXPECT_EQ(FramePattern("frame_%04d.exr").pad(), 4);
  EXPECT_EQ(FramePattern("frame_%d.exr").path(7), "frame_7.exr");
  EXPECT_EQ(FramePattern("frame_%d.exr").pad(), 0);
  EXPECT_EQ(FramePattern("a/100%%_%03d.exr").path(5), "a/100%_005.exr");
}

TEST(FramePattern, SingleFile) {
  const FramePattern p("renders/shot_0042.exr");
  EXPECT_FALSE(p.is_sequence());
  EXPECT_EQ(p.path(1), "renders/shot_0042.exr");
  EXPECT_EQ(p.path(99), "renders/shot_0042.exr");
  EXPECT_EQ(FramePattern("100%%.exr").path(0), "100%.exr");
}

TEST(FramePattern, MalformedPatternsAreUsageErrors) {
  expect_usage_error("a_##_##.exr", "more than one");
  expect_usage_error("a_%04d_#.exr", "more than one");
  expect_usage_error("a_%s.exr", "%s");
  expect_usage_error("a_%04x.exr", "only %d");
  expect_usage_error("a_%5d.exr", "only %d");
  expect_usage_error("a_%.exr", "only %d");
  expect_usage_error("a_%", "only %d");
  expect_usage_error("a_%0d.exr", "%0Nd");
  expect_usage_error("shot_##/beauty.exr", "file name");
}

TEST(FramePattern, ExistingFramesMatchPaddingRules) {
  TempDir dir("hash");
  for (const char* f : {"frame_0001.exr", "frame_0002.exr", "frame_0010.exr", "frame_10000.exr",
                        "frame_001.exr",    // 3 digits: not a 4-pad name
                        "frame_00011.exr",  // 5 digits with a leading zero: not written so
                        "frame_0003.exr.tmp", "frame_0004.EXR", "other_0005.exr", "frame_abcd.exr",
                        "frame_.exr", "xframe_0006.exr", "frame_-001.exr", "frame_-0001.exr",
                        "frame_--01.exr", "frame_-.exr", "frame_-12345.exr"})
    dir.touch(f);
  fs::create_directory(dir.str() + "/frame_0007.exr");  // a directory is not a frame
  const FramePattern p(dir.str() + "/frame_####.exr");
  // Negative frames as printf("%04d") writes them: "-001", not "-0001".
  EXPECT_EQ(p.existing_frames(), (std::vector<int>{-12345, -1, 1, 2, 10, 10000}));
  EXPECT_EQ(FramePattern(dir.str() + "/frame_%04d.exr").existing_frames(),
            (std::vector<int>{-12345, -1, 1, 2, 10, 10000}));
  EXPECT_EQ(FramePattern(dir.str() + "/frame_@@@@.exr").existing_frames(),
            (std::vector<int>{-12345, -1, 1, 2, 10, 10000}));
}

TEST(FramePattern, ExistingFramesUnpadded) {
  TempDir dir("unpadded");
  for (const char* f : {"f_1.exr", "f_12.exr", "f_300.exr", "f_007.exr", "f_0.exr"}) dir.touch(f);
  EXPECT_EQ(FramePattern(dir.str() + "/f_%d.exr").existing_frames(),
            (std::vector<int>{0, 1, 12, 300}));
  EXPECT_EQ(FramePattern(dir.str() + "/f_#.exr").existing_frames(),
            (std::vector<int>{0, 1, 12, 300}));
}

TEST(FramePattern, ExistingFramesEdgeCases) {
  TempDir dir("edge");
  dir.touch("0001.exr");
  dir.touch("0002.exr");
  dir.touch("shot_0042.exr");
  dir.touch("plain.exr");
  // The frame field may start the file name.
  EXPECT_EQ(FramePattern(dir.str() + "/####.exr").existing_frames(), (std::vector<int>{1, 2}));
  // Missing directory: nothing, no error (the caller reports "no frames").
  EXPECT_TRUE(FramePattern(dir.str() + "/missing/f_####.exr").existing_frames().empty());
  // Single files: their own frame number, 0 without digits, nothing when absent.
  EXPECT_EQ(FramePattern(dir.str() + "/shot_0042.exr").existing_frames(), std::vector<int>{42});
  EXPECT_EQ(FramePattern(dir.str() + "/plain.exr").existing_frames(), std::vector<int>{0});
  EXPECT_TRUE(FramePattern(dir.str() + "/absent.exr").existing_frames().empty());
}

TEST(FramePattern, ExistingFramesRelativeToWorkingDirectory) {
  TempDir dir("relative");
  dir.touch("r_0003.exr");
  const fs::path keep = fs::current_path();
  fs::current_path(dir.str());
  const std::vector<int> frames = FramePattern("r_####.exr").existing_frames();
  fs::current_path(keep);
  EXPECT_EQ(frames, std::vector<int>{3});
}

TEST(FrameList, OiiotoolSyntax) {
  using V = std::vector<int>;
  EXPECT_EQ(parse_frame_list("12"), V{12});
  EXPECT_EQ(parse_frame_list("1-8"), (V{1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(parse_frame_list("0-0"), V{0});
  EXPECT_EQ(parse_frame_list("0010-0012"), (V{10, 11, 12}));
  EXPECT_EQ(parse_frame_list("1-9x2"), (V{1, 3, 5, 7, 9}));
  EXPECT_EQ(parse_frame_list("1-10x3"), (V{1, 4, 7, 10}));
  EXPECT_EQ(parse_frame_list("1-10y3"), (V{2, 3, 5, 6, 8, 9}));  // what x3 leaves out
  EXPECT_EQ(parse_frame_list("1,3,5-8"), (V{1, 3, 5, 6, 7, 8}));
  EXPECT_EQ(parse_frame_list("-3--1"), (V{-3, -2, -1}));
  EXPECT_EQ(parse_frame_list("-2-2"), (V{-2, -1, 0, 1, 2}));
  EXPECT_EQ(parse_frame_list("-5"), V{-5});
  // Either direction, repeats once: the frames are computed in ascending order.
  EXPECT_EQ(parse_frame_list("4-1"), (V{1, 2, 3, 4}));
  EXPECT_EQ(parse_frame_list("3,1-3,2"), (V{1, 2, 3}));
  EXPECT_EQ(parse_frame_list("999999990-999999999x9"), (V{999999990, 999999999}));
  EXPECT_EQ(parse_frame_list("-999999999"), V{-999999999});
}

TEST(FrameList, MalformedListsAreUsageErrors) {
  for (const char* bad : {"",
                          "-",
                          "1-",
                          "a",
                          "1-8-9",
                          " 1-8",
                          "1-8 ",
                          "1..8",
                          "1,,3",
                          ",1",
                          "1,",
                          "99999999999",
                          "1-99999999999",
                          "+4",
                          "1-8x0",
                          "1-8x",
                          "3x2",
                          "1-8x-2",
                          "1-8z2",
                          "0-1000000",
                          "1-2y1",
                          "1;2",
                          "1000000000",
                          "-1000000000-0",
                          "-2147483648"}) {
    try {
      parse_frame_list(bad);
      ADD_FAILURE() << "no error for \"" << bad << "\"";
    } catch (const Error& e) {
      EXPECT_EQ(int(e.code()), int(Exit::usage));
      EXPECT_EQ(std::string(e.what()).rfind("--frames: \"" + std::string(bad) + "\": ", 0), 0u)
          << e.what();
    }
  }
  try {
    parse_frame_list("3,x", "--cut-frames");
    ADD_FAILURE() << "no error for 3,x";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--cut-frames: \"3,x\": \"x\" is not a frame"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(parse_frame_list("0-999999").size(), size_t(kMaxFrames));  // the limit itself
  // A very long item is refused, not matched (std::regex recurses per character).
  EXPECT_THROW(parse_frame_list(std::string(1000000, '1')), Error);
}

TEST(FrameList, FormattedListsReadBackAsTheirFrames) {
  using V = std::vector<int>;
  const std::vector<std::pair<V, std::string>> cases = {{{1, 2, 3, 4}, "1-4"},
                                                        {{1, 3, 5, 7}, "1-7x2"},
                                                        {{1, 2, 3, 5}, "1-3,5"},
                                                        {{1, 3}, "1,3"},
                                                        {{-3, -2, -1, 0}, "-3-0"},
                                                        {{7}, "7"},
                                                        {{1, 2, 4, 6, 8, 9}, "1-2,4-8x2,9"},
                                                        {{-10, -5, 0, 5}, "-10-5x5"}};
  for (const auto& [frames, text] : cases) {
    EXPECT_EQ(format_frame_list(frames), text);
    EXPECT_EQ(parse_frame_list(text), frames) << text;
  }
}

TEST(FrameNumberFromName, LastDigitGroupOfTheFileName) {
  EXPECT_EQ(frame_number_from_name("shot_0042.exr"), 42);
  EXPECT_EQ(frame_number_from_name("/r/v2/shot.0007.exr"), 7);
  EXPECT_EQ(frame_number_from_name("take3_frame_0100_beauty.exr"), 100);
  EXPECT_EQ(frame_number_from_name("frame_0001"), 1);
  EXPECT_EQ(frame_number_from_name("dir_12/shot.exr"), std::nullopt);  // not in a directory
  EXPECT_EQ(frame_number_from_name("shot.exr"), std::nullopt);
  EXPECT_EQ(frame_number_from_name("shot_99999999999.exr"), std::nullopt);  // too large
}

}  // namespace
}  // namespace hbil::io
