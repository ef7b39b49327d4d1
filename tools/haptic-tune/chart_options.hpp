// The options every chart command takes (haptic-tune plot, zwidth, plot-run), and their
// checks: the output file and its look (ChartLook); plot and zwidth also take the device,
// the coupling and the models to draw (ChartOptions).
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli_common.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tools {

/// The file a chart goes to and how it looks: PNG, SVG (text kept as text) or PDF by the
/// extension; its size and font size for a paper's column or a slide.
struct ChartLook {
    std::string out;
    std::string out_flag = "--out";  ///< the option that names `out`, for messages
    std::string size = "7x4.8in";    ///< --size WxH[in|cm|mm]
    double font_size_pt = 9.0;       ///< --font-size
    bool json = false;               ///< --json: print the charted data
};
/// The chart file's option (`out_flag`, e.g. --out), --size and --font-size.
void add_chart_file_options(CLI::App& command, ChartLook& look, const std::string& out_flag,
                            const std::string& out_help);
/// --out, --size, --font-size and --json.
void add_chart_look_options(CLI::App& command, ChartLook& look);
/// The figure's width and height in inches from --size: "WxH" with an optional unit
/// (in, cm or mm; in by default), each 1 to 40 in; UsageError naming the value otherwise.
std::pair<double, double> chart_size_in(const std::string& size);
/// The "output" object the chart script reads: path, format, size_in, font_size_pt.
nlohmann::ordered_json chart_output_json(const ChartLook& look);

/// Options plot and zwidth take.
struct ChartOptions {
    DeviceOptions device;
    std::optional<double> stiffness;         ///< k_c (N/m), impedance display
    std::optional<double> coupling_damping;  ///< b_c (N s/m)
    std::string models = "paper,encoder,passive";
    ChartLook look;
    int points = 400;
};
void add_chart_options(CLI::App& command, ChartOptions& options);

/// Checks the option combination shared by every chart: --out is required unless --json,
/// and names a writable .png, .svg or .pdf file; --size is well formed. Throws UsageError
/// naming the value.
void check_chart_output(const ChartLook& look);

/// Image format from the file name's extension (.png, .svg or .pdf, any case); UsageError
/// naming the extension otherwise.
std::string chart_format(const std::string& path, const std::string& flag = "--out");

/// UsageError naming the path unless it can be written: an existing file must be a
/// writable regular file; a new one needs an existing, writable directory.
void check_writable(const std::string& path, const std::string& flag = "--out");

/// "paper,encoder,passive" -> the models in the given order, duplicates dropped; UsageError naming
/// an unknown or empty entry.
std::vector<theory::HoldModel> parse_model_list(const std::string& list);

}  // namespace hapticd::tools
