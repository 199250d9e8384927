// temporaries_test.cpp: the interrupt handling of io/temporaries.h, in child processes (a
// signal there ends the process, as it would end hbil).
#include "io/temporaries.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "test_util.h"

namespace hbil {
namespace {

namespace fs = std::filesystem;

// Runs `body` in a child process with its standard error sent to `err`, and checks that the
// child ended by signal `sig`, not by reaching the end of `body`.
template <class Body>
void expect_child_ended_by(int sig, const std::string& err, Body body) {
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    if (!freopen(err.c_str(), "w", stderr)) _exit(126);
    body();
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit " << WEXITSTATUS(status);
  EXPECT_EQ(WTERMSIG(status), sig);
}

// A SIGTERM raised while a frame is being committed takes effect when the commit ends: the
// code inside the FrameCommit runs to its end, the code after it never runs, the process
// ends by SIGTERM, and the interrupt line counts the frame noted inside.
TEST(FrameCommit, ASignalDuringTheCommitWaitsForItsEnd) {
  test::TempDir dir{test::test_name()};
  const std::string inside = (dir.path() / "inside").string();
  const std::string after = (dir.path() / "after").string();
  const std::string err = (dir.path() / "err.txt").string();
  expect_child_ended_by(SIGTERM, err, [&] {
    io::install_interrupt_cleanup();
    {
      const io::FrameCommit whole;
      raise(SIGTERM);
      io::note_frame_written(7);
      test::write_text(inside, "the commit ran on\n");
    }
    test::write_text(after, "after the commit\n");
  });
  EXPECT_TRUE(fs::exists(inside)) << "the signal cut the commit short";
  EXPECT_FALSE(fs::exists(after)) << "the signal was lost";
  const std::string text = test::read_text(err);
  EXPECT_NE(text.find("hbil: interrupted (signal 15): 1 frame was written (frame 7)"),
            std::string::npos)
      << text;
}

// Outside a commit the signal acts at once, and a run log given to set_interrupt_log gets
// the run's "end" line.
TEST(FrameCommit, ASignalOutsideACommitActsAtOnceAndEndsTheLog) {
  test::TempDir dir{test::test_name()};
  const std::string log = (dir.path() / "run.jsonl").string();
  const std::string after = (dir.path() / "after").string();
  expect_child_ended_by(SIGINT, "/dev/null", [&] {
    std::FILE* f = std::fopen(log.c_str(), "a");
    if (!f) _exit(125);
    io::set_interrupt_log(fileno(f));
    io::install_interrupt_cleanup();
    raise(SIGINT);
    test::write_text(after, "after the signal\n");
  });
  EXPECT_FALSE(fs::exists(after));
  EXPECT_EQ(test::read_text(log),
            "{\"event\":\"end\",\"exit\":130,\"written\":0,\"error\":\"interrupted\","
            "\"signal\":2}\n");
}

}  // namespace
}  // namespace hbil
