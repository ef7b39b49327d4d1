// The one error of haptic-tune autotune's glue: a failure that stops autotune before
// anything was written. The command prints its message and exits 2.
#pragma once

#include <string>

#include "hapticd/input/input_error.hpp"

namespace hapticd::tools {

class AutotuneError : public input::InputError {
  public:
    explicit AutotuneError(const std::string& message) : InputError(message) {}
};

}  // namespace hapticd::tools
