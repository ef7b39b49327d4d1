// The keys of hapticd's config file, each declared once with its unit, range and default
// (input/fields.hpp). config.cpp reads them; docs/daemon.md lists them ("Config"). Where a
// key sets a servo setting, its range and default are the servo's own (servo_config.hpp,
// safety.hpp, ...), so that the daemon and the servo layer cannot disagree; the ranges of
// the physical parameters are the stability models' (tune/input_checks.hpp). Ranges that
// depend on another key (the rate) are functions of it.
#pragma once

#include <optional>
#include <string_view>

#include "hapticd/input/fields.hpp"
#include "hapticd/servo/link_recovery.hpp"
#include "hapticd/servo/passivity.hpp"
#include "hapticd/servo/realtime.hpp"
#include "hapticd/servo/safety.hpp"
#include "hapticd/servo/servo_config.hpp"
#include "hapticd/servo/soft_start.hpp"
#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/operator_class.hpp"
#include "hapticd/tune/stability_check.hpp"

namespace hapticd::daemon {

/// [coupling] check: the start-up stability model; none is check = "off".
using CheckModel = std::optional<tune::StabilityModel>;
std::string_view to_string(CheckModel model) noexcept;

/// [coupling] environments: what the start-up check holds for on the environment side.
enum class EnvironmentClass {
    every_passive,  ///< "every-passive": every passive environment
    scene,          ///< "scene": the scene's own linearised objects
};
std::string_view to_string(EnvironmentClass environments) noexcept;

namespace schema {

using input::Choice;
using input::Flag;
using input::Integer;
using input::Number;
using input::Range;
using input::Text;

// [servo]
inline constexpr Number kRate{"rate_hz", servo::kRateRange, servo::ServoConfig{}.rate_hz};
inline constexpr Choice<servo::RealtimeMode> kRealtime{
    "realtime", servo::kRealtimeModes, &servo::to_string, servo::RealtimeRequest{}.mode};
inline constexpr Integer kPriority{"priority", servo::kMinPriority, servo::kMaxPriority,
                                   servo::RealtimeRequest{}.priority};
inline constexpr Integer kCpu{"cpu", 0, servo::kMaxCpu};  ///< none: the affinity is left alone

// [device]
inline constexpr Text kPlugin{"plugin", "sim", false, "a plugin name such as \"sim\", or a path"};
inline constexpr Integer kAxes{"axes", 1, servo::kMaxAxes, 1};
// [device.model]: no defaults (the start-up check needs them; without them it refuses).
inline constexpr Number kModelMass{
    "mass", {.lo = tune::kMinDeviceMassKg, .hi = tune::kMaxDeviceMassKg, .unit = "kg"}};
inline constexpr Number kModelDamping{
    "damping", {.lo = tune::kMinDeviceDamping, .hi = tune::kMaxDeviceDamping, .unit = "N s/m"}};
/// Coulomb friction F_c (haptic-tune identify's `coulomb`): the identification run's plan
/// predicts with it how long the handle sticks. None: not known (the plan assumes none).
inline constexpr Number kModelCoulomb{"coulomb", {.lo = 0.0, .hi = 1e4, .unit = "N"}};
/// From 0 to below tune::kMaxDelayPeriods periods of the rate (TableReader::read_periods).
inline constexpr Number kModelDelay{"delay", {.lo = 0.0, .unit = "s"}, 0.0};

// [coupling]
inline constexpr Flag kCouplingEnabled{"enabled", servo::ServoConfig{}.coupling_enabled};
inline constexpr Number kCouplingStiffness{
    "stiffness", {.lo = 0.0, .hi = tune::kMaxCouplingStiffness, .unit = "N/m"}, 0.0};
inline constexpr Number kCouplingDamping{
    "damping", {.lo = 0.0, .hi = tune::kMaxCouplingDamping, .unit = "N s/m"}, 0.0};
/// 0 (none), or from tune::kMinVelocityFilterHz to below Nyquist: config.cpp checks it,
/// with a message that says both.
inline constexpr Number kVelocityFilter{"velocity_filter", {.unit = "Hz"}, 0.0};
inline constexpr CheckModel kCheckModels[] = {
    tune::StabilityModel::passive, tune::StabilityModel::exact, tune::StabilityModel::paper,
    tune::StabilityModel::encoder, std::nullopt};
inline constexpr Choice<CheckModel> kCheck{"check", kCheckModels, &daemon::to_string,
                                           tune::StabilityModel::passive};
inline constexpr EnvironmentClass kEnvironmentClasses[] = {EnvironmentClass::every_passive,
                                                           EnvironmentClass::scene};
inline constexpr Choice<EnvironmentClass> kEnvironments{
    "environments", kEnvironmentClasses, &daemon::to_string, EnvironmentClass::every_passive};

// [scene]: none is the embedded demo wall.
inline constexpr Text kSceneFile{"file", std::nullopt, false, "a scene file"};

// [safety]
inline constexpr Number kMaxForce{"max_force", servo::kMaxForceRange,
                                  servo::SafetyLimits{}.max_force_n};
inline constexpr Number kMaxSpeed{"max_speed", servo::kMaxSpeedRange,
                                  servo::SafetyLimits{}.max_speed_mps};
inline constexpr Number kSoftStartRamp{"soft_start_ramp", servo::kRampTimeRange,
                                       servo::SoftStartSettings{}.ramp_time_s};
inline constexpr servo::PassivityMode kPassivityModes[] = {servo::PassivityMode::observe,
                                                           servo::PassivityMode::control};
inline constexpr Choice<servo::PassivityMode> kPassivity{
    "passivity", kPassivityModes, &servo::to_string, servo::PassivitySettings{}.mode};
inline constexpr Flag kReconnect{"reconnect", servo::LinkRecoverySettings{}.enabled};
/// false: the run starts disabled, at zero force, until `hapticctl arm` (needs --socket).
inline constexpr Flag kArmAtStart{"arm_at_start", servo::ServoConfig{}.start_armed};
inline constexpr Number kReconnectSettle{"reconnect_settle", servo::kSettleRange,
                                         servo::LinkRecoverySettings{}.settle_s};
/// 0, or above reconnect_settle (config.cpp checks it).
inline constexpr Number kReconnectTimeout{"reconnect_timeout", servo::kTimeoutRange,
                                          servo::LinkRecoverySettings{}.timeout_s};
inline constexpr Integer kMaxMissedPeriods{"max_missed_periods", 0, servo::kMaxOverrunBudget,
                                           servo::OverrunBudget{}.max_missed_periods};
inline constexpr Integer kMaxConsecutiveOverruns{"max_consecutive_overruns", 0,
                                                 servo::kMaxOverrunBudget,
                                                 servo::OverrunBudget{}.max_consecutive_overruns};

// [identify]: what the config leaves unset, make_identify_plan() chooses at start-up.
/// At most [safety] max_force too (config.cpp checks it).
inline constexpr Number kForceAmplitude{"force_amplitude",
                                        {.lo = 0.0, .hi = 1e4, .lo_open = true, .unit = "N"}};
inline constexpr Number kWorkspace{
    "workspace", {.lo = 0.0, .hi = 1.0, .lo_open = true, .unit = "m"}, 0.03};
/// band_low and band_high: the band stays well below Nyquist, ten samples a cycle at least.
constexpr Number band_edge(std::string_view key, double rate_hz) {
    return {key,
            {.lo = 0.0, .hi = rate_hz / 10.0, .lo_open = true, .unit = "Hz, rate_hz/10 at most"}};
}
inline constexpr Number kLinesPerDecade{
    "lines_per_decade", {.lo = 1.0, .hi = 50.0, .unit = "lines per decade per axis"}, 10.0};
inline constexpr Number kPeriod{"period", {.lo = 0.0, .hi = 60.0, .lo_open = true, .unit = "s"}};
inline constexpr Integer kPeriods{"periods", 1, 1000};
inline constexpr Number kFade{"fade", {.lo = 0.0, .hi = 60.0, .unit = "s"}};

// [operator]: every bound required (a class is a claim about the lab's hands, and a default
// would make it silently); tune::OperatorClass::kKeys and kUnits name them.
inline constexpr Number kMaxResonance{
    "max_resonance",
    {.lo = 0.0, .hi = tune::OperatorClass::kMaxResonanceLimitHz, .lo_open = true, .unit = "Hz"}};

}  // namespace schema
}  // namespace hapticd::daemon
