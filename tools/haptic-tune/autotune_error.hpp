// The one error of haptic-tune autotune's glue: a failure that stops autotune before
// anything was written. The command prints its message and exits 2.
#pragma once

#include <stdexcept>

namespace hapticd::tools {

class AutotuneError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

}  // namespace hapticd::tools
