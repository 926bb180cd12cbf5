// fralab's one error type for bad input (a file, a flag, a message, a number): its message names
// what is wrong and where ("FILE: /json/path: ...", "channel FRALAB_TAPE: ..."), never a crash.
#pragma once

#include <stdexcept>

namespace fralab {

/// Bad user input (a file, a flag, a message): the message names the value and the fix.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace fralab
