// Runs a command-line program for end-to-end tests and captures what it printed.
#pragma once

#include <string>
#include <utility>

#include "child_process.hpp"

namespace hapticd::testing {

struct CommandResult {
    int exit_code = -1;
    std::string out;  ///< standard output
    std::string err;  ///< standard error
};

/// `word` as one word of a /bin/sh command line.
inline std::string shell_quote(const std::string& word) {
    std::string quoted = "'";
    for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

/// Runs `command` through /bin/sh with stdout and stderr captured separately; exit_code is
/// -1 when it did not exit (a signal ended it).
inline CommandResult run_command(const std::string& command) {
    ChildProcess shell({"/bin/sh", "-c", command});
    ChildProcess::Output output = shell.read_output();
    shell.wait();
    return {shell.exited() ? shell.exit_code() : -1, std::move(output.out), std::move(output.err)};
}

}  // namespace hapticd::testing
