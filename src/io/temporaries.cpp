// temporaries.cpp: see temporaries.h.
#include "io/temporaries.h"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstring>
#include <ctime>
#include <mutex>
#include <regex>

#include "hbil/error.h"

namespace hbil::io {

namespace fs = std::filesystem;

namespace {

// The registry the signal handler reads: fixed slots, so that it needs no allocation and no
// lock. A slot is free (0), being filled (1) or holds a temporary's path (2).
constexpr size_t kSlots = 64;
struct Slot {
  std::atomic<int> state{0};
  char path[PATH_MAX];
};
std::array<Slot, kSlots> slots;

std::atomic<int> frames_written{0}, first_written{0}, last_written{0};

// This host's name as it goes into a temporary's name: letters, digits, '.' and '-'.
const std::string& host_tag() {
  static const std::string tag = [] {
    char name[256] = {};
    if (gethostname(name, sizeof name - 1) != 0 || name[0] == 0) std::strcpy(name, "localhost");
    std::string t = name;
    for (char& ch : t)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '.' && ch != '-') ch = '_';
    return t;
  }();
  return tag;
}

void register_temporary(const std::string& path) noexcept {
  if (path.size() >= PATH_MAX) return;  // not removed on an interrupt; a later run removes it
  for (Slot& s : slots) {
    int expected = 0;
    if (!s.state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(s.path, path.c_str(), path.size() + 1);
    s.state.store(2, std::memory_order_release);
    return;
  }
  // All slots taken (more files in flight than any command writes): left to a later run.
}

// Writes `text` and the decimal `v` to `fd`, standard error by default (async-signal-safe).
void say(const char* text, int fd = STDERR_FILENO) noexcept {
  const ssize_t r = ::write(fd, text, std::strlen(text));
  (void)r;
}
void say(int v, int fd = STDERR_FILENO) noexcept {
  char digits[16];
  int n = 0;
  unsigned u = v < 0 ? 0u - unsigned(v) : unsigned(v);
  do digits[n++] = char('0' + u % 10), u /= 10;
  while (u && n < 15);
  char out[17];
  int k = 0;
  if (v < 0) out[k++] = '-';
  while (n) out[k++] = digits[--n];
  out[k] = 0;
  say(out, fd);
}

std::atomic<int> log_fd{-1};  // RunLog's file, for the "end" line of an interrupted run

// A frame's files being renamed into place (FrameCommit): a signal then waits until the frame
// is whole, so that it is either all in place and counted, or not at all.
std::atomic<int> committing{0};
std::atomic<int> pending_signal{0};
// Set by the first interrupt: from then on no thread starts a temporary or a commit (they
// wait to be ended with the process), so that none appears after the handler removed them.
std::atomic<int> dying{0};

[[noreturn]] void wait_for_the_end() noexcept {
  for (;;) pause();
}

void remove_registered() noexcept {
  for (Slot& s : slots)
    if (s.state.load(std::memory_order_acquire) == 2) ::unlink(s.path);
}

extern "C" void on_interrupt(int sig) {
  dying.store(1);
  if (committing.load()) {
    pending_signal.store(sig);
    // Unless the commit ended meanwhile without seeing it: whoever takes it handles it.
    if (committing.load() || pending_signal.exchange(0) == 0) return;
  }
  const int saved = errno;
  // A thread may be creating the file of a temporary it registered just before: the second
  // pass, once such a file is open, removes it (the writers open theirs right after
  // prepare_temporary).
  remove_registered();
  const timespec settle{0, 50 * 1000 * 1000};
  nanosleep(&settle, nullptr);
  remove_registered();
  say("\nhbil: interrupted (signal ");
  say(sig);
  say("): ");
  const int n = frames_written.load();
  if (n == 0) {
    say("no frame was written");
  } else {
    say(n);
    say(n == 1 ? " frame was written (frame " : " frames were written (frames ");
    say(first_written.load());
    if (n > 1) {
      say(" to ");
      say(last_written.load());
    }
    say(")");
  }
  say("; the frame in progress was not, and its temporaries are removed\n");
  // The run log's last line, with what the lines before it cannot say.
  if (const int fd = log_fd.load(); fd >= 0) {
    say("{\"event\":\"end\",\"exit\":", fd);
    say(128 + sig, fd);
    say(",\"written\":", fd);
    say(n, fd);
    say(",\"error\":\"interrupted\",\"signal\":", fd);
    say(sig, fd);
    say("}\n", fd);
  }
  errno = saved;
  // The default action again: the process ends by this signal once the handler returns.
  signal(sig, SIG_DFL);
  raise(sig);
}

}  // namespace

std::string prepare_temporary(const std::string& final_path, const std::string& tag) {
  const fs::path final_p(final_path);
  std::error_code ec;
  if (final_p.has_parent_path()) {
    fs::create_directories(final_p.parent_path(), ec);
    if (ec)
      throw Error(Exit::output, final_path + ": cannot create folder " +
                                    final_p.parent_path().string() + ": " + ec.message());
  }
  static std::atomic<int> counter{0};
  // Appended piece by piece: "." + std::string trips GCC 12's -Wrestrict (a false positive).
  std::string name = ".";
  name += final_p.stem().string();
  name += ".hbil-tmp-";
  if (!tag.empty()) name += tag + "-";
  name += host_tag() + "-" + std::to_string(getpid()) + "-" + std::to_string(counter++);
  name += final_p.extension().string();
  const std::string path = (final_p.parent_path() / name).string();
  register_temporary(path);
  if (dying.load()) wait_for_the_end();  // interrupted: the file is not to be created
  return path;
}

void release_temporary(const std::string& temporary) noexcept {
  for (Slot& s : slots)
    if (s.state.load(std::memory_order_acquire) == 2 && temporary == s.path) {
      s.state.store(0, std::memory_order_release);
      return;
    }
}

void discard_temporary(const std::string& temporary) noexcept {
  std::error_code ec;
  fs::remove(temporary, ec);
  release_temporary(temporary);
}

void install_interrupt_cleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    host_tag();  // computed here, not in the handler
    struct sigaction sa {};
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // on_interrupt restores the default action itself
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction old {};
      // A signal the caller ignores (nohup, a shell's background job) stays ignored.
      if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
      sigaction(sig, &sa, nullptr);
    }
  });
}

FrameCommit::FrameCommit() noexcept {
  committing.fetch_add(1);
  if (dying.load()) {
    // Interrupted: no new commit. A signal left to the commits in flight is handled by the
    // last of them, which may be this one.
    if (committing.fetch_sub(1) == 1)
      if (const int sig = pending_signal.exchange(0)) on_interrupt(sig);
    wait_for_the_end();
  }
}
FrameCommit::~FrameCommit() {
  if (committing.fetch_sub(1) != 1) return;
  if (const int sig = pending_signal.exchange(0)) on_interrupt(sig);
}

void set_interrupt_log(int fd) noexcept {
  log_fd.store(fd);
}

void note_frame_written(int frame) noexcept {
  if (frames_written.fetch_add(1) == 0) first_written.store(frame);
  last_written.store(frame);
}

int remove_stale_temporaries(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return 0;
  // .STEM.hbil-tmp-[TAG-]HOST-PID-N.EXT: the host, the process and the counter from the right
  // (a host name may hold dots and dashes).
  static const std::regex name(R"(^\..*\.hbil-tmp-(.*)-([0-9]{1,9})-[0-9]+(\.[A-Za-z0-9]*)?$)");
  const std::string& host = host_tag();
  int removed = 0;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string file = it->path().filename().string();
    std::smatch m;
    if (!std::regex_match(file, m, name)) continue;
    const std::string who = m[1].str();
    if (who.size() < host.size() || who.compare(who.size() - host.size(), host.size(), host) != 0)
      continue;
    const std::string tag = who.substr(0, who.size() - host.size());
    if (tag != "" && tag != "display-" && tag != "pov-") continue;  // another host's
    const long pid = std::stol(m[2].str());
    if (pid <= 0 || pid == long(getpid())) continue;
    if (kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // still running (or not ours)
    std::error_code rm;
    if (it->is_regular_file(rm) && fs::remove(it->path(), rm)) ++removed;
  }
  return removed;
}

}  // namespace hbil::io
