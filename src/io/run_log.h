// run_log.h: `hbil run --log-json FILE`, a log that machines read: one JSON object per line
// (JSON Lines), appended to FILE and flushed line by line, so that a farm can follow a task
// while it runs and a rerun adds to what an earlier run logged. man hbil, --log-json, gives
// the events and their keys.
#pragma once

#include <cstdio>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

namespace hbil::io {

class RunLog {
 public:
  RunLog() = default;  // a log that writes nothing until opened
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  // Opens `path` for appending (its folder is created); Error(Exit::output) naming the file
  // when it cannot be. The file also receives the "end" line of an interrupted run
  // (temporaries.h).
  void open(const std::string& path);
  bool enabled() const { return file_ != nullptr; }
  // Adds `event` (an object; its "event" key first) as one line; callable from any thread. A
  // failing write is an Error(Exit::output) naming the file.
  void write(const std::string& event, nlohmann::ordered_json fields);

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::mutex mutex_;
};

}  // namespace hbil::io
