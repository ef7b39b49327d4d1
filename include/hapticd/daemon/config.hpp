// hapticd's configuration file (TOML): [servo], [device], [device.model], [device.<plugin>]
// (the plugin's own table, read by the plugin: device/plugin_table.hpp), [coupling],
// [operator] (a declared operator class: tune/operator_class.hpp), [scene], [safety] and
// [identify]. Every key is declared once, with its unit, range, default and help, in
// config_schema.hpp, bound to its member by the field lists below, and read with the one
// field reader (input/table_reader.hpp): unknown keys and tables are errors, and each
// message names the file, the line, the key, the value and the allowed range. Mode strings
// end here: the sections hold enums. The reference of the keys is config_keys_markdown()
// (docs/daemon.md, "Config"; `hapticd --config-keys`).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hapticd/daemon/config_schema.hpp"
#include "hapticd/input/config_error.hpp"
#include "hapticd/input/field_list.hpp"
#include "hapticd/tune/operator_class.hpp"

namespace hapticd::daemon {

/// Bad input in a config, a scene, an operator class or a plugin's table (exit 2).
using input::ConfigError;

// Each table's struct, and beside it its field list (input/field_list.hpp): which key sets
// which member. The reader fills the structs from the lists; `hapticd --config-keys` and
// docs/daemon.md's table print them. Where the servo has a settings struct of its own
// (LinkRecoverySettings, OverrunBudget, SoftStartSettings), the section holds it.

struct ServoSection {
    std::string name = std::string(*schema::kName.default_value);
    double rate_hz = *schema::kRate.default_value;
    servo::RealtimeMode realtime = schema::kRealtime.default_value;
    int priority = static_cast<int>(*schema::kPriority.default_value);
    std::optional<int> cpu;
};
inline constexpr auto kServoFields =
    input::fields<ServoSection>("servo", input::bind(schema::kName, &ServoSection::name),
                                input::bind(schema::kRate, &ServoSection::rate_hz),
                                input::bind(schema::kRealtime, &ServoSection::realtime),
                                input::bind(schema::kPriority, &ServoSection::priority),
                                input::bind(schema::kCpu, &ServoSection::cpu));

/// [device.model]: the device model the start-up check uses.
struct DeviceModel {
    std::optional<double> mass_kg;
    std::optional<double> damping_n_s_per_m;
    std::optional<double> coulomb_n;                      ///< the identify plan uses it
    double delay_s = *schema::kModelDelay.default_value;  ///< sample to force, beyond the hold
    /// delay is written in the file (delay_s is its value); false: delay_s is the default.
    /// haptic-tune autotune tells a stated delay from none.
    bool delay_stated = false;
};
inline constexpr auto kDeviceModelFields = input::fields<DeviceModel>(
    "device.model", input::bind(schema::kModelMass, &DeviceModel::mass_kg),
    input::bind(schema::kModelDamping, &DeviceModel::damping_n_s_per_m),
    input::bind(schema::kModelCoulomb, &DeviceModel::coulomb_n),
    input::bind(schema::kModelDelay, &DeviceModel::delay_s));

struct DeviceSection {
    std::string plugin = std::string(*schema::kPlugin.default_value);
    int axes = static_cast<int>(*schema::kAxes.default_value);
    DeviceModel model;
    /// The TOML document that holds the plugin's own table (the config's own text, so that
    /// the plugin's messages carry its lines), and where in it: "device.<plugin>". The
    /// plugin reads and validates it (device/plugin_table.hpp).
    std::string plugin_table_toml;
    std::string plugin_table_path;
};
inline constexpr auto kDeviceFields =
    input::fields<DeviceSection>("device", input::bind(schema::kPlugin, &DeviceSection::plugin),
                                 input::bind(schema::kAxes, &DeviceSection::axes));

struct CouplingSection {
    bool enabled = schema::kCouplingEnabled.default_value;
    double stiffness_n_per_m = *schema::kCouplingStiffness.default_value;
    double damping_n_s_per_m = *schema::kCouplingDamping.default_value;
    /// 0: no filter on the damper's velocity
    double velocity_filter_hz = *schema::kVelocityFilter.default_value;
    CheckModel check = schema::kCheck.default_value;  ///< none: check = "off"
    EnvironmentClass environments = schema::kEnvironments.default_value;
};
inline constexpr auto kCouplingFields = input::fields<CouplingSection>(
    "coupling", input::bind(schema::kCouplingEnabled, &CouplingSection::enabled),
    input::bind(schema::kCouplingStiffness, &CouplingSection::stiffness_n_per_m),
    input::bind(schema::kCouplingDamping, &CouplingSection::damping_n_s_per_m),
    input::bind(schema::kVelocityFilter, &CouplingSection::velocity_filter_hz),
    input::bind(schema::kCheck, &CouplingSection::check),
    input::bind(schema::kEnvironments, &CouplingSection::environments));

/// [scene]: the file as written; Config::scene_file is it resolved.
struct SceneSection {
    std::optional<std::string> file;
};
inline constexpr auto kSceneFields =
    input::fields<SceneSection>("scene", input::bind(schema::kSceneFile, &SceneSection::file));

struct SafetySection {
    double max_force_n = *schema::kMaxForce.default_value;
    double max_speed_mps = *schema::kMaxSpeed.default_value;
    servo::SoftStartSettings soft_start;  ///< soft_start_ramp: its ramp_time_s
    servo::PassivityMode passivity = schema::kPassivity.default_value;
    bool arm_at_start = schema::kArmAtStart.default_value;
    /// reconnect, reconnect_settle, reconnect_timeout (0: wait for ever).
    servo::LinkRecoverySettings reconnect;
    /// max_missed_periods, max_consecutive_overruns: one overrun that misses more periods,
    /// or more overrunning ticks in a row, latches overrun_budget.
    servo::OverrunBudget overrun;
};
inline constexpr auto kSafetyFields = input::fields<SafetySection>(
    "safety", input::bind(schema::kMaxForce, &SafetySection::max_force_n),
    input::bind(schema::kMaxSpeed, &SafetySection::max_speed_mps),
    input::bind(schema::kSoftStartRamp, &SafetySection::soft_start,
                &servo::SoftStartSettings::ramp_time_s),
    input::bind(schema::kPassivity, &SafetySection::passivity),
    input::bind(schema::kReconnect, &SafetySection::reconnect,
                &servo::LinkRecoverySettings::enabled),
    input::bind(schema::kArmAtStart, &SafetySection::arm_at_start),
    input::bind(schema::kReconnectSettle, &SafetySection::reconnect,
                &servo::LinkRecoverySettings::settle_s),
    input::bind(schema::kReconnectTimeout, &SafetySection::reconnect,
                &servo::LinkRecoverySettings::timeout_s),
    input::bind(schema::kMaxMissedPeriods, &SafetySection::overrun,
                &servo::OverrunBudget::max_missed_periods),
    input::bind(schema::kMaxConsecutiveOverruns, &SafetySection::overrun,
                &servo::OverrunBudget::max_consecutive_overruns));

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
inline constexpr auto kIdentifyFields = input::fields<IdentifySection>(
    "identify", input::bind(schema::kForceAmplitude, &IdentifySection::force_amplitude_n),
    input::bind(schema::kWorkspace, &IdentifySection::workspace_m),
    input::bind(schema::kBandLow, &IdentifySection::band_low_hz),
    input::bind(schema::kBandHigh, &IdentifySection::band_high_hz),
    input::bind(schema::kLinesPerDecade, &IdentifySection::lines_per_decade),
    input::bind(schema::kPeriod, &IdentifySection::period_s),
    input::bind(schema::kPeriods, &IdentifySection::periods),
    input::bind(schema::kFade, &IdentifySection::fade_s));

struct Config {
    std::string source;    ///< the file name, or "<embedded default>"
    std::string base_dir;  ///< relative paths (the scene file) resolve against this
    /// SHA-256 of the config's text as read, in hex: what the telemetry's preamble names it by.
    std::string sha256;
    ServoSection servo;
    DeviceSection device;
    CouplingSection coupling;
    std::string scene_file;  ///< [scene] file resolved; empty means the embedded demo scene
    SafetySection safety;
    IdentifySection identify;
    /// [operator]: a declared operator class; none means every passive operator.
    std::optional<tune::OperatorClass> operators;
};

/// The reference of every key (but [operator]'s and the plugins' tables) as a Markdown
/// table: key, allowed, default, meaning. docs/daemon.md holds it; `hapticd --config-keys`
/// prints it.
std::string config_keys_markdown();

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
