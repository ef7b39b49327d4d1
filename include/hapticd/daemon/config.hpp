// hapticd's configuration file (TOML), with the keys DESIGN.md fixes:
//
//   [servo]        rate_hz (Hz, 100..20000), realtime ("enforce"|"warn"|"off"),
//                  priority (SCHED_FIFO 1..99), cpu (core to pin the servo thread to, >= 0)
//   [device]       plugin (a name such as "sim", or a path to a .so), axes (1..3)
//   [device.model] mass (kg, 1e-4..1e3), damping (N s/m, 1e-4..1e4): the model the start-up
//                  check uses; delay (s, >= 0 and < 10 periods, default 0): the time from
//                  the encoder sample to the force taking effect, beyond the hold
//                  (haptic-tune diag measures it)
//   [device.<plugin>]  the plugin's own table, handed to it as TOML text; it validates it
//   [coupling]     stiffness (N/m, >= 0), damping (N s/m, >= 0),
//                  velocity_filter (Hz, 0 (default: none) or >= 1 and < rate_hz/2: the
//                  cutoff of a first-order low-pass on the damper's velocity),
//                  check ("passive" (default)|"exact"|"paper"|"encoder"|"off", the start-up
//                  stability model; paper and encoder are not a guarantee and say so),
//                  enabled (default true; false: no coupling, the scene's forces act on the
//                  device directly: the conventional design, for experiments; needs
//                  check = "off" and no gains),
//                  environments ("every-passive" (default) | "scene": check against the
//                  scene's own linearised objects instead of every passive environment;
//                  check passive or exact; a scene with a detent or friction is refused)
//   [scene]        file (a scene TOML, relative to this file's folder)
//   [safety]       max_force (N, > 0), max_speed (m/s, > 0),
//                  soft_start_ramp (s, 0..10, default 0.5: force ramp after a still handle),
//                  passivity ("observe" | "control": Hannaford and Ryu's time-domain
//                  passivity controller adds damping when the observed energy goes negative),
//                  reconnect (default true: a latch of link faults only, device_lost,
//                  read_timeout, device_io, clears by itself once the device has sent good
//                  samples for reconnect_settle s, (0, 60], default 0.5; if it has not within
//                  reconnect_timeout s of the fault, 0 (wait for ever) or (settle, 3600],
//                  default 5, the run ends on the fault; false: any fault ends the run)
//   [identify]     the excitation of `hapticd --identify` (docs/daemon.md; ignored otherwise):
//                  force_amplitude (N, > 0, <= [safety] max_force: each axis's peak),
//                  workspace (m, (0, 1], default 0.03: half-width of the box about the
//                  start), band_low, band_high (Hz, > 0, <= rate_hz/10, low < high),
//                  lines_per_decade (1..50, default 10), period (s, (0, 60]),
//                  periods (1..1000), fade (s, 0..60). Unset values are chosen at start-up
//                  from [device.model] (make_identify_plan, daemon/servo_settings.hpp);
//                  without [device.model], force_amplitude is required
//   [operator]     a declared operator class for check = "exact" (tune/operator_class.hpp):
//                  hand_mass (kg, (0, 1e3]), grip_stiffness, arm_stiffness (N/m, [0, 1e7]),
//                  grip_damping, arm_damping (N s/m, [0, 1e4]), each a number or [min, max],
//                  all required; max_resonance (Hz, optional): the hand's own highest
//                  resonance. Absent: every passive operator
//
// Every key is checked for type and range, and unknown keys and tables are errors. Each
// message names the file, the key, the value and the allowed range.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hapticd/tune/operator_class.hpp"

namespace hapticd::daemon {

class ConfigError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

struct ServoSection {
    double rate_hz = 1000.0;
    std::string realtime = "warn";
    int priority = 80;
    std::optional<int> cpu;
};

struct DeviceSection {
    std::string plugin = "sim";
    int axes = 1;
    std::optional<double> model_mass_kg;
    std::optional<double> model_damping_n_s_per_m;
    double model_delay_s = 0.0;  ///< sample to force, beyond the hold
    /// [device.<plugin>] as TOML text (empty when absent), for the plugin to validate.
    std::string plugin_table_toml;
};

struct CouplingSection {
    bool enabled = true;
    double stiffness_n_per_m = 0.0;
    double damping_n_s_per_m = 0.0;
    double velocity_filter_hz = 0.0;  ///< 0: no filter on the damper's velocity
    std::string check = "passive";
    /// "every-passive" (default) or "scene": the environments the check holds for.
    std::string environments = "every-passive";
};

struct SafetySection {
    double max_force_n = 10.0;
    double max_speed_mps = 1.0;
    double soft_start_ramp_s = 0.5;
    std::string passivity = "observe";
    bool reconnect = true;
    double reconnect_settle_s = 0.5;
    double reconnect_timeout_s = 5.0;  ///< 0: wait for ever
    /// The overrun budget (servo::OverrunBudget): one overrun that misses more periods, or
    /// more overrunning ticks in a row, latches overrun_budget.
    std::int64_t max_missed_periods = 20;
    int max_consecutive_overruns = 5;
};

/// [identify]: what the config says; make_identify_plan() fills what it leaves unset.
struct IdentifySection {
    std::optional<double> force_amplitude_n;  ///< each axis's peak force, N
    double workspace_m = 0.03;                ///< half-width of the box about the start, m
    std::optional<double> band_low_hz;
    std::optional<double> band_high_hz;
    double lines_per_decade = 10.0;  ///< per axis
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
/// the scene path. Throws ConfigError.
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
