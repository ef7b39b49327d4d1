// Shared pieces of the chart commands (haptic-tune plot, haptic-tune zwidth): their
// options, the coupling design a chart is drawn for, the frequency axis, the output file,
// and rendering. C++ computes every number; tools/plot/hapticd_chart.py only draws them.
//
// Rendering runs the script with Debian's /usr/bin/python3 (env HAPTICD_PYTHON overrides)
// and sends it the chart as one JSON document on its standard input. The script is found
// through env HAPTICD_CHART_SCRIPT, else the build-tree path, else the installed path.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tools {

/// The chart could not be drawn (no python, no matplotlib, the script failed). Reported
/// like a usage error: exit 2, with what to install or what went wrong.
class ChartError : public UsageError {
  public:
    using UsageError::UsageError;
};

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

/// `points` frequencies in hertz, geometric (even on a log axis) from
/// min(0.1 Hz, Nyquist/1000) up to the Nyquist frequency, which is the last element.
std::vector<double> chart_frequencies_hz(double rate_hz, int points);

/// The spring-damper coupling (16) a chart is drawn for, and where it came from.
struct ImpedanceDesign {
    theory::SpringDamperCoupling coupling;
    /// "flags" (--stiffness), "config" ([coupling] stiffness) or "sized" (neither given:
    /// sized from (21) with the passive model, and the delay, for the given damping).
    std::string source;
    double sized_binding_frequency_hz = 0.0;  ///< only for source == "sized"
};
/// k_c from --stiffness, else [coupling] stiffness, else size_impedance_coupling with the
/// passive model and the input's delay; b_c from --coupling-damping, else [coupling] damping, else
/// 0.
ImpedanceDesign resolve_impedance_design(const ChartOptions& options, const DesignInput& input);

/// JSON of the design, for --json and the chart.
nlohmann::ordered_json design_json(const ImpedanceDesign& design);

/// "k_c = 4000 N/m, b_c = 0 N s/m" and, when sized, "(sized with the passive model)".
std::string describe_design(const ImpedanceDesign& design);
/// "m = 0.1 kg, b = 2 N s/m, 1000 Hz servo".
std::string describe_device(const DesignInput& input);

/// A number for titles and messages: up to 4 significant digits.
std::string format_number(double value);

/// Draws `chart` (its "kind" selects the chart: "design-procedure" or "zwidth") into
/// `out_path` in `format`. Throws ChartError when the chart cannot be drawn.
void render_chart(nlohmann::ordered_json chart, const std::string& out_path,
                  const std::string& format);

/// Runs `python script` with `input` on its standard input; returns its exit code and
/// what it printed (stdout and stderr together). Throws ChartError when it cannot start.
struct ScriptRun {
    int exit_code = -1;
    int signal = 0;
    std::string output;
};
ScriptRun run_python_script(const std::string& python, const std::string& script,
                            const std::string& input);

}  // namespace hapticd::tools
