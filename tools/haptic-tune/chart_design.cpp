#include "chart_design.hpp"

#include <algorithm>
#include <cmath>

#include "hapticd/install/version.hpp"
#include "hapticd/theory/unit_circle.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tools {

std::vector<double> chart_frequencies_hz(double rate_hz, int points) {
    const double nyquist = theory::nyquist_hz(1.0 / rate_hz);
    const double lowest = std::min(0.1, nyquist / 1000.0);
    std::vector<double> frequencies(static_cast<std::size_t>(points));
    const double ratio = std::log(nyquist / lowest);
    for (int i = 0; i < points; ++i) {
        frequencies[static_cast<std::size_t>(i)] =
            lowest * std::exp(ratio * static_cast<double>(i) / static_cast<double>(points - 1));
    }
    frequencies.front() = lowest;
    frequencies.back() = nyquist;
    return frequencies;
}

ImpedanceDesign resolve_impedance_design(const ChartOptions& options, const DesignInput& input) {
    tune::check_device(input.device);
    tune::check_rate(input.rate_hz);
    ImpedanceDesign design;
    design.coupling.damping_n_s_per_m =
        options.coupling_damping.value_or(input.coupling_damping_n_s_per_m.value_or(0.0));
    design.coupling.velocity_filter_hz = input.velocity_filter_hz;
    if (options.stiffness) {
        design.coupling.stiffness_n_per_m = *options.stiffness;
        design.source = "flags";
    } else if (input.coupling_stiffness_n_per_m) {
        design.coupling.stiffness_n_per_m = *input.coupling_stiffness_n_per_m;
        design.source = "config";
    } else {
        tune::ImpedanceSizingRequest request;
        request.device = input.device;
        request.rate_hz = input.rate_hz;
        request.model = {theory::HoldModel::passive, input.delay_periods()};
        request.coupling_damping_n_s_per_m = design.coupling.damping_n_s_per_m;
        request.velocity_filter_hz = design.coupling.velocity_filter_hz;
        const tune::ImpedanceSizing sizing = tune::size_impedance_coupling(request);
        design.coupling = sizing.coupling;
        design.source = "sized";
        design.sized_binding_frequency_hz = sizing.binding_frequency_hz;
    }
    if (design.coupling.renders_nothing()) {
        throw UsageError("--stiffness 0 with --coupling-damping 0 is no coupling at all");
    }
    return design;
}

nlohmann::ordered_json design_json(const ImpedanceDesign& design) {
    nlohmann::ordered_json out = {{"stiffness", design.coupling.stiffness_n_per_m},
                                  {"damping", design.coupling.damping_n_s_per_m},
                                  {"velocity_filter_hz", design.coupling.velocity_filter_hz},
                                  {"source", design.source}};
    if (design.source == "sized") {
        out["sizing_model"] = "passive";
        out["sizing_binding_frequency_hz"] = design.sized_binding_frequency_hz;
    }
    return out;
}

std::string describe_design(const ImpedanceDesign& design) {
    std::string text = "k_c = " + number_text(design.coupling.stiffness_n_per_m, 4) +
                       " N/m, b_c = " + number_text(design.coupling.damping_n_s_per_m, 4) +
                       " N s/m";
    if (design.coupling.velocity_filter_hz > 0.0) {
        text +=
            " on a " + number_text(design.coupling.velocity_filter_hz, 4) + " Hz velocity filter";
    }
    if (design.source == "sized") text += " (sized from (21) with the passive model)";
    if (design.source == "config") text += " (from [coupling] in the config)";
    return text;
}

std::string describe_device(const DesignInput& input) {
    return "m = " + number_text(input.device.mass_kg, 4) +
           " kg, b = " + number_text(input.device.damping_n_s_per_m, 4) + " N s/m, " +
           number_text(input.rate_hz, 4) + " Hz servo";
}

std::string model_names(const std::vector<theory::HoldModel>& models) {
    std::string names;
    for (const theory::HoldModel model : models) {
        names += (names.empty() ? "" : ", ") + std::string(theory::to_string(model));
    }
    return names;
}

std::string chart_caption(const std::string& what, const std::string& models,
                          const DesignInput& input) {
    const std::string delay = input.delay_s > 0.0
                                  ? "loop delay " + number_text(input.delay_s * 1e3, 4) + " ms (" +
                                        number_text(input.delay_periods(), 4) + " periods)"
                                  : "no loop delay";
    const std::string source =
        input.config ? " (" + input.config->source + ")" : std::string(" (flags)");
    return what + "; models " + models + "; device " + describe_device(input) + ", " + delay +
           source + "; hapticd " + install::kVersion;
}

}  // namespace hapticd::tools
