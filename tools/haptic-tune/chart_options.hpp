// The options every chart command (haptic-tune plot, haptic-tune zwidth) takes, and their
// checks: the device, the coupling, the models to draw, the output file.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tools {

/// Options every chart command takes.
struct ChartOptions {
    DeviceOptions device;
    std::optional<double> stiffness;         ///< k_c (N/m), impedance display
    std::optional<double> coupling_damping;  ///< b_c (N s/m)
    std::string models = "paper,encoder,passive";
    std::string out;
    int points = 400;
    bool json = false;
};
void add_chart_options(CLI::App& command, ChartOptions& options);

/// Checks the option combination shared by every chart: --out is required unless --json,
/// and names a writable .png or .svg file. Throws UsageError naming the value.
void check_chart_output(const ChartOptions& options);

/// Image format from the file name's extension (.png or .svg, any case); UsageError
/// naming the extension otherwise.
std::string chart_format(const std::string& path);

/// UsageError naming the path unless it can be written: an existing file must be a
/// writable regular file; a new one needs an existing, writable directory.
void check_writable(const std::string& path);

/// "paper,encoder,passive" -> the models in the given order, duplicates dropped; UsageError naming
/// an unknown or empty entry.
std::vector<theory::HoldModel> parse_model_list(const std::string& list);

}  // namespace hapticd::tools
