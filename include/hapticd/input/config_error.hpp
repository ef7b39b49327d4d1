// The one error type of bad input in a file hapticd or haptic-tune reads: the config, a
// scene, an operator class, a plugin's table (and a file that cannot be read at all). Its
// message is final: it names the file, the line where known, the key, the value and what
// is allowed (table_reader.hpp has the format). Every command exits 2 on it.
#pragma once

#include <string>

#include "hapticd/input/input_error.hpp"

namespace hapticd::input {

class ConfigError : public InputError {
  public:
    explicit ConfigError(const std::string& message) : InputError(message, "config error") {}
};

}  // namespace hapticd::input
