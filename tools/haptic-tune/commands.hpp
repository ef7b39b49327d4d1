// The haptic-tune subcommands. Each adds itself to the application and, when chosen,
// sets the Invocation that main() runs.
#pragma once

#include <CLI/CLI.hpp>

#include "cli_common.hpp"

namespace hapticd::tools {

void add_size_command(CLI::App& app, Invocation& invocation);
void add_check_command(CLI::App& app, Invocation& invocation);
void add_plot_command(CLI::App& app, Invocation& invocation);
void add_zwidth_command(CLI::App& app, Invocation& invocation);
void add_plot_run_command(CLI::App& app, Invocation& invocation);
void add_diag_command(CLI::App& app, Invocation& invocation);
void add_identify_command(CLI::App& app, Invocation& invocation);
void add_autotune_command(CLI::App& app, Invocation& invocation);
void add_conform_command(CLI::App& app, Invocation& invocation);

}  // namespace hapticd::tools
