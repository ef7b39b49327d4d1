// The one base of every error that means bad input: a command line, a config, a scene, a log,
// a device table, an output path or a design that cannot be had (hapticd, haptic-tune and
// hapticctl all read it the same way). Its message is final: it names the file, key or value
// and what is allowed. Every command exits kExitCode (2) on it, before anything moves; the
// top of each program has one catch for it and one for everything else (a fault, exit 1).
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace hapticd::input {

class InputError : public std::runtime_error {
  public:
    /// The exit status of every hapticd command on bad input (daemon::kExitBadInput).
    static constexpr int kExitCode = 2;

    /// `kind` names the error before its message where a command prints one ("haptic-tune:
    /// config error: ..."): a string literal.
    explicit InputError(const std::string& message, const char* kind = "error")
        : std::runtime_error(message), kind_(kind) {}

    std::string_view kind() const noexcept { return kind_; }

  private:
    const char* kind_;
};

/// `error` with `before` in front of its message and `after` behind it, of the same kind:
/// throw with_context("bad log: ", e) where a caller knows what the input was for.
inline InputError with_context(std::string_view before, const InputError& error,
                               std::string_view after = {}) {
    return InputError(std::string(before) + error.what() + std::string(after), error.kind().data());
}

}  // namespace hapticd::input
