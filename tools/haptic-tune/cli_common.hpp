// Shared pieces of the haptic-tune subcommands: exit codes, validated numeric options,
// the device description (flags or a config file), and result printing.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tools {

/// Exit codes shared by every hapticd command (DESIGN.md): 0 success (or stable),
/// 1 a negative verdict (not stable), 2 usage or input error.
enum ExitCode : int { kExitOk = 0, kExitVerdictNo = 1, kExitUsage = 2 };

/// What the chosen subcommand runs once the command line has parsed.
struct Invocation {
    std::function<int()> run;
};

/// Bad input found after parsing (a missing value, an inconsistent combination).
class UsageError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// CLI11 validators that name the allowed range and reject NaN and infinities.
CLI::Validator positive_finite(std::string unit);
CLI::Validator non_negative_finite(std::string unit);

/// The device and servo rate a design is for: from flags, or from a hapticd config file
/// ([device.model] mass, damping; [servo] rate_hz; [coupling] stiffness, damping),
/// flags overriding the file.
struct DeviceOptions {
    std::string config_path;
    std::optional<double> mass_kg;
    std::optional<double> damping_n_s_per_m;
    std::optional<double> rate_hz;
    std::optional<double> delay_s;             ///< --delay, where the command takes it
    std::optional<double> velocity_filter_hz;  ///< --velocity-filter, where the command takes it
};
void add_device_options(CLI::App& command, DeviceOptions& options);
/// --delay SECONDS: the loop delay from the encoder sample to the force taking effect,
/// beyond the zero-order hold ([device.model] delay in a config).
void add_delay_option(CLI::App& command, DeviceOptions& options);
/// --velocity-filter HZ: the cutoff of the first-order low-pass on the coupling damper's
/// velocity ([coupling] velocity_filter in a config); 0 (default) is none.
void add_velocity_filter_option(CLI::App& command, DeviceOptions& options);

/// --model for size/check/plot: `allowed` (the first is the default, passive).
void add_model_option(CLI::App& command, std::string& model,
                      const std::vector<std::string>& allowed);

struct DesignInput {
    theory::DeviceModel device;
    double rate_hz = 0.0;
    std::optional<double> coupling_stiffness_n_per_m;  ///< from [coupling] if present
    std::optional<double> coupling_damping_n_s_per_m;
    double delay_s = 0.0;  ///< checked: >= 0 and < 10 periods
    double delay_periods() const { return delay_s * rate_hz; }
    double velocity_filter_hz = 0.0;  ///< checked: 0, or 1 Hz up to below rate/2
};
/// Merges the config file and the flags; throws UsageError naming what is missing or a
/// value out of its range (device, rate, delay, velocity filter).
DesignInput resolve_design_input(const DeviceOptions& options);

/// Prints `fields` as aligned "key  value" lines, or as one JSON object with --json.
void print_result(const nlohmann::ordered_json& fields, bool json);

}  // namespace hapticd::tools
