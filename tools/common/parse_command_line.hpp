// How hapticd, haptic-tune and hapticctl read their command line with CLI11, in one place:
// --help and --version print and exit 0; anything CLI11 refuses prints its
// message and the usage hint and exits 2 (kExitBadInput: docs/architecture.md §4.7).
#pragma once

#include <CLI/CLI.hpp>
#include <optional>

#include "hapticd/daemon/exit_code.hpp"

namespace hapticd::tools {

/// Parses `argv` into `app`: nullopt to go on, else the status the program exits with.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& help) {
        return app.exit(help);
    } catch (const CLI::CallForVersion& version) {
        return app.exit(version);
    } catch (const CLI::ParseError& error) {
        app.exit(error);
        return daemon::kExitBadInput;
    }
    return std::nullopt;
}

}  // namespace hapticd::tools
