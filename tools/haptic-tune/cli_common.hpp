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

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/exit_code.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/input/input_error.hpp"
#include "hapticd/input/range.hpp"
#include "hapticd/theory/admittance.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tools {

// The exit codes every hapticd command shares (daemon/exit_code.hpp).
using daemon::kExitBadInput;
using daemon::kExitOk;
using daemon::kExitVerdictNo;

/// What the chosen subcommand runs once the command line has parsed.
struct Invocation {
    std::function<int()> run;
};

/// Bad input found after parsing (a missing value, an inconsistent combination).
class UsageError : public input::InputError {
  public:
    explicit UsageError(const std::string& message) : InputError(message) {}
};

/// CLI11 validators that name the allowed range and reject NaN and infinities.
CLI::Validator positive_finite(const std::string& unit);
CLI::Validator non_negative_finite(const std::string& unit);
/// Within `range` (servo::kRateRange for --rate): the refusal reads as the config reader's,
/// "value 50 is out of range: allowed >= 100 and <= 20000 (Hz)".
CLI::Validator in_range(const input::Range& range);

/// A hapticd config file read exactly as hapticd reads it: daemon::load_config, then the
/// [device] plugin's check of its own table (daemon::check_device_config), at the same point.
/// A plugin that cannot be loaded is refused with the message hapticd gives for it. Throws
/// daemon::ConfigError. Every command that takes --config reads it with this.
daemon::Config load_config_as_hapticd(const std::string& path);

/// The device and servo rate a design is for: from flags, or from a hapticd config file read
/// exactly as hapticd reads it (daemon::load_config: [device.model] mass, damping, delay;
/// [servo] rate_hz; [coupling] stiffness, damping, velocity_filter), flags overriding it.
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
CLI::Option* add_model_option(CLI::App& command, std::string& model,
                              const std::vector<std::string>& allowed);

/// --display impedance|admittance, and the admittance display's PI velocity-loop gains
/// --kp and --ki (size, zwidth).
struct DisplayOptions {
    std::string display = "impedance";
    std::optional<double> kp;
    std::optional<double> ki;

    bool admittance() const { return display == "admittance"; }
    /// The PI loop of --kp and --ki; throws UsageError when either is missing.
    theory::PiVelocityLoop pi_loop() const;
};
void add_display_options(CLI::App& command, DisplayOptions& options);

struct DesignInput {
    theory::DeviceModel device;
    double rate_hz = 0.0;
    /// [coupling] stiffness when the config has a spring (> 0): plot and zwidth size one
    /// otherwise.
    std::optional<double> coupling_stiffness_n_per_m;
    std::optional<double> coupling_damping_n_s_per_m;  ///< [coupling] damping, with a config
    double delay_s = 0.0;                              ///< checked: >= 0 and < 10 periods
    double delay_periods() const { return delay_s * rate_hz; }
    double velocity_filter_hz = 0.0;  ///< checked: 0, or 1 Hz up to below rate/2
    /// The whole config, as hapticd read it (none without --config).
    std::optional<daemon::Config> config;
};
/// Merges the config file and the flags; throws UsageError naming what is missing or a
/// flag out of its range (device, rate, delay, velocity filter), daemon::ConfigError for
/// the config (its message is the one hapticd gives).
DesignInput resolve_design_input(const DeviceOptions& options);
/// The input a result was computed for, after the result's own fields: delay_s,
/// delay_periods, device {mass, damping} and rate_hz.
void add_input_fields(const DesignInput& input, nlohmann::ordered_json& out);

/// `text` without leading and trailing white space.
std::string trimmed(const std::string& text);

/// A number for messages and titles with `digits` significant digits: "0.1", "4000".
std::string number_text(double value, int digits = 6);

/// Prints `fields` as aligned "key  value" lines, or as one JSON object with --json.
void print_result(const nlohmann::ordered_json& fields, bool json);

}  // namespace hapticd::tools
