// What a chart is drawn for and along (haptic-tune plot, haptic-tune zwidth): the coupling
// design, its description, and the frequency axis. C++ computes every number a chart shows;
// the chart script only draws them (chart_script.hpp).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "chart_options.hpp"
#include "cli_common.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tools {

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

/// The names of `models`, comma separated: "paper, encoder, passive".
std::string model_names(const std::vector<theory::HoldModel>& models);

/// A chart's caption line (the chart script adds the date): what is drawn, the models, the
/// device with its loop delay and where it came from, and the version:
/// "haptic-tune plot; models paper, passive; device m = 0.1 kg, b = 2 N s/m, 1000 Hz servo,
/// no loop delay (config/devices/pen-display.toml); hapticd 0.1.0".
std::string chart_caption(const std::string& what, const std::string& models,
                          const DesignInput& input);

}  // namespace hapticd::tools
