// run_log.cpp: see run_log.h.
#include "io/run_log.h"

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "hbil/error.h"
#include "io/temporaries.h"

namespace hbil::io {

namespace fs = std::filesystem;

void RunLog::open(const std::string& path) {
  path_ = path;
  const fs::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  if (fs::is_directory(p, ec)) throw Error(Exit::output, "--log-json " + path + ": is a folder");
  file_ = std::fopen(path.c_str(), "a");
  if (!file_)
    throw Error(Exit::output, "--log-json " + path + ": cannot open: " + std::strerror(errno));
  set_interrupt_log(fileno(file_));
}

RunLog::~RunLog() {
  if (!file_) return;
  set_interrupt_log(-1);
  std::fclose(file_);
}

void RunLog::write(const std::string& event, nlohmann::ordered_json fields) {
  if (!file_) return;
  nlohmann::ordered_json line;
  line["event"] = event;
  for (auto& [k, v] : fields.items()) line[k] = std::move(v);
  // Strings that are not UTF-8 (a file name) are written with U+FFFD, not refused.
  const std::string text =
      line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
  const std::lock_guard<std::mutex> lock(mutex_);
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size() || std::fflush(file_) != 0)
    throw Error(Exit::output, "--log-json " + path_ + ": cannot write: " + std::strerror(errno));
}

}  // namespace hbil::io
