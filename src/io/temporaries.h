// temporaries.h: the hidden temporary files every output is written to before it is renamed
// into place, and what becomes of them when a run is interrupted or killed.
//
// A temporary is named `.STEM.hbil-tmp-[TAG-]HOST-PID-N.EXT` beside its final file: the host
// and the process that writes it, and a counter (TAG: display for display images, pov for
// imported POV-Ray frames). While the process runs, its temporaries
// are registered here:
//  - on SIGINT, SIGTERM or SIGHUP (install_interrupt_cleanup) the registered ones are
//    removed, one line says which frames were written, and the signal's default action
//    ends the process (the shell reports 128 + the signal: 130, 143, 129);
//  - a process killed outright (SIGKILL, power loss) leaves its temporaries; the next run
//    that writes into the same folder removes those whose process is gone
//    (remove_stale_temporaries). Only temporaries of this host are judged: on a shared
//    folder another node's process cannot be seen from here.
#pragma once

#include <filesystem>
#include <string>
#include <utility>

namespace hbil::io {

// The temporary for `final_path` (creating its folder), registered for removal on an
// interrupt. Throws Error(Exit::output) when the folder cannot be made.
std::string prepare_temporary(const std::string& final_path, const std::string& tag = "");
// A temporary that was renamed into place or removed: no longer to be removed on an interrupt.
void release_temporary(const std::string& temporary) noexcept;
// Removes a temporary (a write that failed) and releases it.
void discard_temporary(const std::string& temporary) noexcept;

// A temporary being written: removed (and released) when the writing fails, unless keep()
// handed it on.
class Temporary {
 public:
  explicit Temporary(const std::string& final_path, const std::string& tag = "")
      : path_(prepare_temporary(final_path, tag)) {}
  ~Temporary() {
    if (!path_.empty()) discard_temporary(path_);
  }
  Temporary(const Temporary&) = delete;
  Temporary& operator=(const Temporary&) = delete;
  const std::string& path() const { return path_; }
  // The finished temporary, still registered, for the caller to commit.
  std::string keep() { return std::exchange(path_, std::string()); }

 private:
  std::string path_;
};

// Installs the SIGINT, SIGTERM and SIGHUP handlers described above (once per process).
void install_interrupt_cleanup();
// A frame whose files were all renamed into place: the interrupt line names the frames.
void note_frame_written(int frame) noexcept;
// Held while a frame's files are renamed into place and noted as written: an interrupt that
// arrives meanwhile takes effect when the last FrameCommit ends, so that a frame is never
// left with its EXR in place and its display image removed, nor in place and not counted.
class FrameCommit {
 public:
  FrameCommit() noexcept;
  ~FrameCommit();
  FrameCommit(const FrameCommit&) = delete;
  FrameCommit& operator=(const FrameCommit&) = delete;
};

// The file descriptor (open for appending) of `run --log-json`, or -1: an interrupt adds the
// run's "end" line to it.
void set_interrupt_log(int fd) noexcept;

// Removes, in `dir`, the temporaries of processes of this host that no longer run; returns
// how many. A folder that does not exist holds none.
int remove_stale_temporaries(const std::filesystem::path& dir);

}  // namespace hbil::io
