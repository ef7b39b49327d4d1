// hapticd's configuration file (TOML), with the keys docs/architecture.md §5.3 names (their units,
// ranges and defaults: config_schema.hpp; the table of them: docs/daemon.md "Config"):
//
//   [servo]        rate_hz, realtime ("enforce"|"warn"|"off"), priority (SCHED_FIFO),
//                  cpu (the core to pin the servo thread to)
//   [device]       plugin (a name such as "sim", or a path to a .so), axes
//   [device.model] mass, damping: the model the start-up check uses; delay: the time from
//                  the encoder sample to the force taking effect, beyond the hold, below
//                  10 periods (haptic-tune diag measures it)
//   [device.<plugin>]  the plugin's own table, left where it is in the file for the plugin
//                  to read and validate (device/plugin_table.hpp)
//   [coupling]     stiffness, damping, velocity_filter (0: none, or from 1 Hz to below
//                  Nyquist: the cutoff of a first-order low-pass on the damper's velocity),
//                  check ("passive"|"exact"|"paper"|"encoder"|"off", the start-up stability
//                  model; paper and encoder are not a guarantee and say so),
//                  enabled (false: no coupling, the scene's forces act on the device
//                  directly: the conventional design, for experiments; needs check = "off"
//                  and no gains),
//                  environments ("every-passive" | "scene": check against the scene's own
//                  linearised objects instead of every passive environment; check passive
//                  or exact; a scene with a detent or friction is refused)
//   [scene]        file (a scene TOML, relative to this file's folder)
//   [safety]       max_force, max_speed, soft_start_ramp (force ramp after a still handle),
//                  passivity ("observe" | "control": Hannaford and Ryu's time-domain
//                  passivity controller adds damping when the observed energy goes negative),
//                  reconnect (true: a latch of link faults only, device_lost, read_timeout,
//                  device_io, clears by itself once the device has sent good samples for
//                  reconnect_settle s; if it has not within reconnect_timeout s of the fault
//                  (0: wait for ever; else above the settle), the run ends on the fault;
//                  false: any fault ends the run), max_missed_periods,
//                  max_consecutive_overruns (the overrun budget)
//   [identify]     the excitation of `hapticd --identify` (docs/daemon.md; ignored otherwise):
//                  force_amplitude (each axis's peak, at most [safety] max_force), workspace
//                  (half-width of the box about the start), band_low, band_high (at most
//                  rate_hz/10, low < high), lines_per_decade, period, periods, fade. Unset
//                  values are chosen at start-up from [device.model] (make_identify_plan,
//                  daemon/servo_settings.hpp); without [device.model], force_amplitude is
//                  required
//   [operator]     a declared operator class for check = "exact" (tune/operator_class.hpp):
//                  hand_mass, grip_stiffness, arm_stiffness, grip_damping, arm_damping, each
//                  a number or [min, max], all required; max_resonance (Hz, optional): the
//                  hand's own highest resonance. Absent: every passive operator
//
// Every key is declared once, with its unit, range and default, in config_schema.hpp, and
// read with the one field reader (input/table_reader.hpp): unknown keys and tables are
// errors, and each message names the file, the line, the key, the value and the allowed
// range. Mode strings end here: the sections hold enums.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hapticd/daemon/config_schema.hpp"
#include "hapticd/input/config_error.hpp"
#include "hapticd/tune/operator_class.hpp"

namespace hapticd::daemon {

/// Bad input in a config, a scene, an operator class or a plugin's table (exit 2).
using input::ConfigError;

struct ServoSection {
    double rate_hz = *schema::kRate.default_value;
    servo::RealtimeMode realtime = schema::kRealtime.default_value;
    int priority = static_cast<int>(*schema::kPriority.default_value);
    std::optional<int> cpu;
};

struct DeviceSection {
    std::string plugin = std::string(*schema::kPlugin.default_value);
    int axes = static_cast<int>(*schema::kAxes.default_value);
    std::optional<double> model_mass_kg;
    std::optional<double> model_damping_n_s_per_m;
    std::optional<double> model_coulomb_n;  ///< Coulomb friction; the identify plan uses it
    double model_delay_s =
        *schema::kModelDelay.default_value;  ///< sample to force, beyond the hold
    /// [device.model] delay is written in the file (model_delay_s is its value); false:
    /// model_delay_s is the default. haptic-tune autotune tells a stated delay from none.
    bool model_delay_stated = false;
    /// The TOML document that holds the plugin's own table (the config's own text, so that
    /// the plugin's messages carry its lines), and where in it: "device.<plugin>". The
    /// plugin reads and validates it (device/plugin_table.hpp).
    std::string plugin_table_toml;
    std::string plugin_table_path;
};

struct CouplingSection {
    bool enabled = schema::kCouplingEnabled.default_value;
    double stiffness_n_per_m = *schema::kCouplingStiffness.default_value;
    double damping_n_s_per_m = *schema::kCouplingDamping.default_value;
    /// 0: no filter on the damper's velocity
    double velocity_filter_hz = *schema::kVelocityFilter.default_value;
    CheckModel check = schema::kCheck.default_value;  ///< none: check = "off"
    EnvironmentClass environments = schema::kEnvironments.default_value;
};

struct SafetySection {
    double max_force_n = *schema::kMaxForce.default_value;
    double max_speed_mps = *schema::kMaxSpeed.default_value;
    double soft_start_ramp_s = *schema::kSoftStartRamp.default_value;
    servo::PassivityMode passivity = schema::kPassivity.default_value;
    bool reconnect = schema::kReconnect.default_value;
    bool arm_at_start = schema::kArmAtStart.default_value;
    double reconnect_settle_s = *schema::kReconnectSettle.default_value;
    double reconnect_timeout_s = *schema::kReconnectTimeout.default_value;  ///< 0: wait for ever
    /// The overrun budget (servo::OverrunBudget): one overrun that misses more periods, or
    /// more overrunning ticks in a row, latches overrun_budget.
    std::int64_t max_missed_periods = *schema::kMaxMissedPeriods.default_value;
    int max_consecutive_overruns = static_cast<int>(*schema::kMaxConsecutiveOverruns.default_value);
};

/// [identify]: what the config says; make_identify_plan() fills what it leaves unset.
struct IdentifySection {
    std::optional<double> force_amplitude_n;  ///< each axis's peak force, N
    double workspace_m =
        *schema::kWorkspace.default_value;  ///< half-width of the box about the start, m
    std::optional<double> band_low_hz;
    std::optional<double> band_high_hz;
    double lines_per_decade = *schema::kLinesPerDecade.default_value;  ///< per axis
    std::optional<double> period_s;
    std::optional<int> periods;
    std::optional<double> fade_s;
};

struct Config {
    std::string source;    ///< the file name, or "<embedded default>"
    std::string base_dir;  ///< relative paths (the scene file) resolve against this
    ServoSection servo;
    DeviceSection device;
    CouplingSection coupling;
    std::string scene_file;  ///< resolved path; empty means the embedded demo scene
    SafetySection safety;
    IdentifySection identify;
    /// [operator]: a declared operator class; none means every passive operator.
    std::optional<tune::OperatorClass> operators;
};

/// Parses and validates config text. `source` names it in messages; `base_dir` resolves
/// the scene path. Throws ConfigError. haptic-tune reads a config with this too.
Config parse_config(std::string_view toml_text, const std::string& source,
                    const std::string& base_dir);

/// Reads and parses a config file. Throws ConfigError (also for an unreadable file).
Config load_config(const std::string& path);

/// The [operator] table of a TOML file (an operator class file, or a hapticd config; its
/// other tables are not read). Throws ConfigError when it is absent or invalid.
tune::OperatorClass load_operator_class(const std::string& path);

/// The embedded default: the simulated device and the demo wall scene (config/hapticd.toml
/// and config/scenes/demo-wall.toml, compiled in).
Config default_config();
std::string_view default_config_text();
std::string_view default_scene_text();

}  // namespace hapticd::daemon
