// preset_file.cpp: see preset_file.h.
#include "io/preset_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "hbil/error.h"

namespace hbil::io {

Params read_preset(const std::string& path) {
  // Missing or unreadable is a preset error (exit 7) like a malformed one, named by path.
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw Error(Exit::preset, "--preset " + path + ": file not found");
  if (std::filesystem::is_directory(path, ec))
    throw Error(Exit::preset, "--preset " + path + ": is a folder, not a JSON file");
  std::ifstream in(path);
  if (!in) throw Error(Exit::preset, "--preset " + path + ": cannot read: " + std::strerror(errno));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {  // parse_error, or out_of_range (1e999)
    throw Error(Exit::preset, path + ": not valid JSON: " + e.what());
  }
  return params_from_json(j, path);
}

}  // namespace hbil::io
