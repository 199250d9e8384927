// error.h: the one error type of hbil and its exit codes.
//
// Library code throws hbil::Error with a category and a message that already names
// the file, frame and layer involved. Only main() turns it into a message and an exit
// code (see man/hbil.1, EXIT STATUS). The numeric values are part of the interface.
#pragma once

#include <stdexcept>
#include <string>

namespace hbil {

enum class Exit : int {
  ok = 0,
  failure = 1,       // internal error, unexpected exception
  usage = 2,         // bad command line
  input = 3,         // input file missing, unreadable or not an EXR
  missing_pass = 4,  // a pass the requested outputs need is absent
  bad_data = 5,      // non-finite / negative depth, resolution change, ...
  camera = 6,        // no usable camera, or solved camera too inaccurate
  preset = 7,        // unknown key, out-of-range value, malformed JSON
  output = 8,        // output cannot be written
  incomplete = 9,    // farm check: frames of the plan are not done
};

class Error : public std::runtime_error {
 public:
  Error(Exit code, const std::string& message) : std::runtime_error(message), code_(code) {}
  Exit code() const { return code_; }

 private:
  Exit code_;
};

}  // namespace hbil
