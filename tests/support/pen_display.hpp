// The device of every HIL test: the paper's benchmark pen display (Fig. 2), m = 0.1 kg,
// b = 2 N s/m, at 1 kHz, with a 10 um encoder and a 20 N force limit; the same numbers in
// [device.model] (what the start-up check assumes) and [device.sim] (what the plant is).
// These helpers write hapticd's config TOML for it (include/hapticd/daemon/config.hpp,
// docs/sim-device.md).
#pragma once

#include <array>
#include <charconv>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::testing {

inline constexpr double kPenMassKg = 0.1;
inline constexpr double kPenDampingNsPerM = 2.0;
inline constexpr double kRateHz = 1000.0;
inline constexpr double kPeriodS = 1.0 / kRateHz;
inline constexpr double kCountsPerMeter = 1e5;
inline constexpr double kCountM = 1.0 / kCountsPerMeter;  ///< one encoder count, 10 um
inline constexpr double kForceLimitN = 20.0;
/// Colgate and Schenkel's stiffness bound for this device, 2b/T = 4000 N/m.
inline constexpr double kColgateStiffnessNPerM = 2.0 * kPenDampingNsPerM / kPeriodS;

/// A number as TOML, in the shortest form that reads back to the same double.
inline std::string toml_number(double value) {
    std::array<char, 64> buffer{};
    const auto [end, error] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
    std::string text(buffer.data(), error == std::errc{} ? end : buffer.data());
    if (text.find_first_of(".en") == std::string::npos) text += ".0";  // 100000 -> 100000.0
    return text;
}

/// A TOML array of numbers.
inline std::string toml_vector(const std::vector<double>& values) {
    std::string text = "[";
    for (std::size_t i = 0; i < values.size(); ++i)
        text += (i ? ", " : "") + toml_number(values[i]);
    return text + "]";
}

struct CouplingGains {
    double stiffness_n_per_m = 0.0;   ///< k_c of (16)
    double damping_n_s_per_m = 0.0;   ///< b_c of (16)
    double velocity_filter_hz = 0.0;  ///< [coupling] velocity_filter; 0: none (not written)
};

/// [coupling] with the virtual coupling (16) and the start-up check `check`.
inline std::string coupling_table(const CouplingGains& gains, std::string_view check) {
    std::string text = "[coupling]\nstiffness = " + toml_number(gains.stiffness_n_per_m) +
                       "\ndamping = " + toml_number(gains.damping_n_s_per_m) + "\ncheck = \"" +
                       std::string(check) + "\"\n";
    if (gains.velocity_filter_hz > 0.0) {
        text += "velocity_filter = " + toml_number(gains.velocity_filter_hz) + "\n";
    }
    return text;
}

/// [coupling] without a coupling: the scene's penalty force acts on the handle directly.
inline std::string no_coupling_table() { return "[coupling]\nenabled = false\ncheck = \"off\"\n"; }

/// push = { to, start, ramp, hold } of a grasp's set-point (docs/sim-device.md).
inline std::string push_toml(double to_m, double start_s, double ramp_s, double hold_s) {
    return "push = { to = " + toml_number(to_m) + ", start = " + toml_number(start_s) +
           ", ramp = " + toml_number(ramp_s) + ", hold = " + toml_number(hold_s) + " }\n";
}

/// One operator for every axis: [device.sim.human] with `body` (its keys).
inline std::string human_table(const std::string& body) { return "[device.sim.human]\n" + body; }

/// One operator per axis: [[device.sim.human]] once per body, in axis order.
inline std::string per_axis_human_tables(const std::vector<std::string>& bodies) {
    std::string text;
    for (const std::string& body : bodies) text += "[[device.sim.human]]\n" + body;
    return text;
}

/// hapticd's config for the pen display (1 to 3 identical axes) on the sim plugin.
struct DaemonConfig {
    int axes = 1;
    std::string coupling;                  ///< a [coupling] table (coupling_table() ...)
    std::string initial_position = "0.0";  ///< TOML: a number, or an array of `axes`
    std::string humans;                    ///< [device.sim.human] table(s); empty: hands-off
    std::string sim_keys;                  ///< more [device.sim] keys, e.g. "delay = 0.001\n"
    /// More [device.model] keys (what the start-up check assumes), e.g. "delay = 0.001\n".
    std::string model_keys;
    double counts_per_meter = kCountsPerMeter;  ///< the sim's encoder
    std::string faults;                         ///< the body of [device.sim.faults]; empty: none
    std::string sim_clock = "lockstep";
    std::string realtime = "off";
    std::string passivity = "observe";
    double max_force_n = kForceLimitN;
    double max_speed_mps = 1.0;
    double soft_start_ramp_s = 0.5;
    std::string scene_file = "scene.toml";
    std::string safety_keys;  ///< more [safety] keys, e.g. "max_missed_periods = 1000\n"

    std::string toml() const {
        std::string text;
        text +=
            "[servo]\nrate_hz = " + toml_number(kRateHz) + "\nrealtime = \"" + realtime + "\"\n";
        text += "[device]\nplugin = \"sim\"\naxes = " + std::to_string(axes) + "\n";
        text += "[device.model]\nmass = " + toml_number(kPenMassKg) +
                "\ndamping = " + toml_number(kPenDampingNsPerM) + "\n" + model_keys;
        text += coupling;
        text += "[scene]\nfile = \"" + scene_file + "\"\n";
        text += "[safety]\nmax_force = " + toml_number(max_force_n) +
                "\nmax_speed = " + toml_number(max_speed_mps) +
                "\nsoft_start_ramp = " + toml_number(soft_start_ramp_s) + "\npassivity = \"" +
                passivity + "\"\n" + safety_keys;
        text += "[device.sim]\nmass = " + toml_number(kPenMassKg) +
                "\ndamping = " + toml_number(kPenDampingNsPerM) +
                "\ncounts_per_meter = " + toml_number(counts_per_meter) +
                "\nforce_limit = " + toml_number(kForceLimitN) + "\nclock = \"" + sim_clock +
                "\"\ninitial_position = " + initial_position + "\n";
        text += sim_keys;
        text += humans;
        if (!faults.empty()) text += "[device.sim.faults]\n" + faults;
        return text;
    }
};

}  // namespace hapticd::testing
