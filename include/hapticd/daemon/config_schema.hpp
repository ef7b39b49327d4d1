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
/// A label for this instance, in the summary, the control socket's status and the journal.
inline constexpr Text kName{
    "name",
    "",
    true,
    "free text",
    "a label for this instance (\"left arm\", \"rig 2\"): the summary's and the control "
    "socket's status' `name`, the journal's start line, and the first line of its logs and "
    "recordings, `# name: NAME`",
    64};
inline constexpr Number kRate{"rate_hz", servo::kRateRange, servo::ServoConfig{}.rate_hz,
                              "servo rate, T = 1/rate"};
inline constexpr Choice<servo::RealtimeMode> kRealtime{
    "realtime", servo::kRealtimeModes, &servo::to_string, servo::RealtimeRequest{}.mode,
    "SCHED_FIFO on the servo thread, mlockall with prefaulting, CPU affinity, "
    "`/dev/cpu_dma_latency` held; `enforce` refuses to run without all of them, `warn` "
    "reports what was refused"};
inline constexpr Integer kPriority{
    "priority", servo::kMinPriority,  servo::kMaxPriority, servo::RealtimeRequest{}.priority,
    "",         "SCHED_FIFO priority"};
/// None: the affinity is left alone.
inline constexpr Integer kCpu{
    "cpu",
    0,
    servo::kMaxCpu,
    std::nullopt,
    "",
    "pin the servo thread to this CPU (one this machine has, checked before the servo "
    "thread starts) and keep hapticd's other threads (watcher, control socket, log writer, "
    "reconnect) off it: the summary's `realtime.other_threads_cpus` lists where they run "
    "(`other_threads_not_off` why not, when they could not be kept off); not with "
    "`realtime = \"off\"` or a lockstep device"};

// [device]
inline constexpr Text kPlugin{"plugin", "sim", false, "a plugin name such as \"sim\", or a path",
                              "the device plugin (`hapticd --list-plugins`); its own table "
                              "is `[device.<plugin>]` (`[device.sim]`: docs/sim-device.md)"};
inline constexpr Integer kAxes{"axes", 1, servo::kMaxAxes, 1, "", "must equal what the device has"};
// [device.model]: no defaults (the start-up check needs them; without them it refuses).
inline constexpr Number kModelMass{
    "mass",
    {.lo = tune::kMinDeviceMassKg, .hi = tune::kMaxDeviceMassKg, .unit = "kg"},
    std::nullopt,
    "the device's mass m, for the start-up check (measure it with `haptic-tune identify`)"};
inline constexpr Number kModelDamping{
    "damping",
    {.lo = tune::kMinDeviceDamping, .hi = tune::kMaxDeviceDamping, .unit = "N s/m"},
    std::nullopt,
    "the device's damping b, for the start-up check (`haptic-tune identify`)"};
/// Coulomb friction F_c (haptic-tune identify's `coulomb`): the identification run's plan
/// predicts with it how long the handle sticks. None: not known (the plan assumes none).
inline constexpr Number kModelCoulomb{
    "coulomb",
    {.lo = 0.0, .hi = 1e4, .unit = "N"},
    std::nullopt,
    "the Coulomb friction `haptic-tune identify` reports (none: no friction assumed): `hapticd "
    "--identify` refuses an excitation under which the handle would stick too long"};
/// From 0 to below tune::kMaxDelayPeriods periods of the rate (TableReader::read_periods).
inline constexpr Number kModelDelay{
    "delay",
    {.lo = 0.0, .unit = "s"},
    0.0,
    "the time from the encoder sample to the force taking effect, beyond the zero-order hold "
    "(host, bus and device); the start-up check includes it (docs/stability-models.md; "
    "`haptic-tune diag` measures it)",
    ">= 0 and < 10 periods of [servo] rate_hz (s)"};
static_assert(tune::kMaxDelayPeriods == 10.0, "kModelDelay's rule states 10 periods");

// [coupling]
inline constexpr Flag kCouplingEnabled{
    "enabled", servo::ServoConfig{}.coupling_enabled,
    "false: no coupling, the scene's penalty forces act on the device directly (the "
    "conventional design, for experiments); needs `check = \"off\"` and no gains; not for "
    "constraint scenes"};
inline constexpr Number kCouplingStiffness{
    "stiffness",
    {.lo = 0.0, .hi = tune::kMaxCouplingStiffness, .unit = "N/m"},
    0.0,
    "k_c of (16); size it with `haptic-tune size`"};
inline constexpr Number kCouplingDamping{
    "damping", {.lo = 0.0, .hi = tune::kMaxCouplingDamping, .unit = "N s/m"}, 0.0, "b_c of (16)"};
/// 0 (none), or from tune::kMinVelocityFilterHz to below Nyquist: config.cpp checks it,
/// with a message that says both.
inline constexpr Number kVelocityFilter{
    "velocity_filter",
    {.unit = "Hz"},
    0.0,
    "cutoff f_c of a first-order low-pass on the damper's velocity, u[n] = a u[n-1] + (1 - "
    "a)(v_d - v_e), a = exp(-2 pi f_c T), in Z_c of every stability model "
    "(docs/stability-models.md); emptied whenever the coupling restarts",
    "0 (no filter) or >= 1 and < rate_hz/2 (Hz)"};
static_assert(tune::kMinVelocityFilterHz == 1.0, "kVelocityFilter's rule states 1 Hz");
inline constexpr CheckModel kCheckModels[] = {
    tune::StabilityModel::passive, tune::StabilityModel::exact, tune::StabilityModel::paper,
    tune::StabilityModel::encoder, std::nullopt};
inline constexpr Choice<CheckModel> kCheck{
    "check", kCheckModels, &daemon::to_string, tune::StabilityModel::passive,
    "the start-up stability model (docs/stability-models.md); `paper` and `encoder` are no "
    "guarantee and say so; `off` checks nothing and says so"};
inline constexpr EnvironmentClass kEnvironmentClasses[] = {EnvironmentClass::every_passive,
                                                           EnvironmentClass::scene};
inline constexpr Choice<EnvironmentClass> kEnvironments{
    "environments", kEnvironmentClasses, &daemon::to_string, EnvironmentClass::every_passive,
    "what the check holds for on the environment side: every passive environment, or the "
    "scene's own linearised objects (check passive or exact; not a scene with a detent or "
    "friction)"};

// [scene]: none is the embedded demo wall.
inline constexpr Text kSceneFile{"file", std::nullopt, false, "a scene file",
                                 "the scene, relative to the config's folder "
                                 "(docs/scenes.md); none: the embedded demo wall"};

// [safety]
inline constexpr Number kMaxForce{
    "max_force", servo::kMaxForceRange, servo::SafetyLimits{}.max_force_n,
    "force saturation (vector norm), also capped at the device's own limit"};
inline constexpr Number kMaxSpeed{
    "max_speed", servo::kMaxSpeedRange, servo::SafetyLimits{}.max_speed_mps,
    "above it the safety stage adds damping; an encoder step of ten times this in one "
    "period is a jump fault"};
inline constexpr Number kSoftStartRamp{
    "soft_start_ramp", servo::kRampTimeRange, servo::SoftStartSettings{}.ramp_time_s,
    "force ramp after the handle is still: tick k of the ramp commands at most k T/ramp of "
    "the saturated force (a handle that starts inside an object is entered through it)"};
inline constexpr servo::PassivityMode kPassivityModes[] = {servo::PassivityMode::observe,
                                                           servo::PassivityMode::control};
inline constexpr Choice<servo::PassivityMode> kPassivity{
    "passivity", kPassivityModes, &servo::to_string, servo::PassivitySettings{}.mode,
    "Hannaford and Ryu's passivity observer; `control` adds damping when the energy flowing "
    "out to the user goes negative"};
/// false: the run starts disabled, at zero force, until `hapticctl arm` (needs --socket).
inline constexpr Flag kArmAtStart{
    "arm_at_start", servo::ServoConfig{}.arm_at_start,
    "false: the run starts disabled, at zero force, and waits for `hapticctl arm` (then the "
    "handle must be still, then the ramp); needs `--socket` (the unit gives it), else exit 2"};
inline constexpr Flag kReconnect{
    "reconnect", servo::LinkRecoverySettings{}.enabled,
    "a link fault (device_lost, read_timeout, device_io) clears by itself once the device has "
    "sent good samples for reconnect_settle; false: every fault ends the run"};
inline constexpr Number kReconnectSettle{
    "reconnect_settle", servo::kSettleRange, servo::LinkRecoverySettings{}.settle_s,
    "how long the device must send good samples without a break before the link-fault latch "
    "clears"};
/// 0, or above reconnect_settle (config.cpp checks it).
inline constexpr Number kReconnectTimeout{
    "reconnect_timeout", servo::kTimeoutRange, servo::LinkRecoverySettings{}.timeout_s,
    "the device must be back and settled within this time of the fault, or the run ends "
    "with exit 1; 0: wait for ever; else above reconnect_settle"};
inline constexpr Integer kMaxMissedPeriods{
    "max_missed_periods",
    0,
    servo::kMaxOverrunBudget,
    servo::OverrunBudget{}.max_missed_periods,
    "",
    "the overrun budget: one overrun (a late wake, a host stall) that misses more periods "
    "latches `overrun_budget`, and the summary names the stall"};
inline constexpr Integer kMaxConsecutiveOverruns{
    "max_consecutive_overruns",
    0,
    servo::kMaxOverrunBudget,
    servo::OverrunBudget{}.max_consecutive_overruns,
    "",
    "... as do more overrunning ticks than this in a row"};

// [identify]: what the config leaves unset, make_identify_plan() chooses at start-up.
/// At most [safety] max_force too (config.cpp checks it).
inline constexpr Number kForceAmplitude{
    "force_amplitude",
    {.lo = 0.0, .hi = 1e4, .lo_open = true, .unit = "N"},
    std::nullopt,
    "each axis's peak force, at most [safety] max_force; none: the largest for which "
    "[device.model] predicts a swing of half the workspace, at most half the force limit "
    "(required without [device.model])"};
inline constexpr Number kWorkspace{"workspace",
                                   {.lo = 0.0, .hi = 1.0, .lo_open = true, .unit = "m"},
                                   0.03,
                                   "half-width of the box about the still handle at the start"};
/// band_low and band_high: the band stays well below Nyquist, ten samples a cycle at least.
constexpr Number band_edge(const Number& edge, double rate_hz) {
    return {edge.key,
            {.lo = 0.0, .hi = rate_hz / 10.0, .lo_open = true, .unit = "Hz, rate_hz/10 at most"}};
}
inline constexpr Number kBandLow{
    "band_low",
    {.unit = "Hz"},
    std::nullopt,
    "no line below it; none: f_c/2 with f_c = b/(2 pi m) of [device.model], 1 Hz without it",
    "> 0 and <= rate_hz/10 (Hz)"};
inline constexpr Number kBandHigh{
    "band_high",
    {.unit = "Hz"},
    std::nullopt,
    "no line above it, above band_low; none: min(10 f_c, rate_hz/20), min(30 Hz, "
    "rate_hz/20) without a model",
    "> 0 and <= rate_hz/10 (Hz)"};
inline constexpr Number kLinesPerDecade{
    "lines_per_decade",
    {.lo = 1.0, .hi = 50.0, .unit = "lines per decade per axis"},
    10.0,
    "grid density per axis (several axes share the grid, line by line in turn)"};
inline constexpr Number kPeriod{"period",
                                {.lo = 0.0, .hi = 60.0, .lo_open = true, .unit = "s"},
                                std::nullopt,
                                "T_p: the lines are whole harmonics of 1/T_p; none: 4/band_low"};
inline constexpr Integer kPeriods{"periods",
                                  1,
                                  1000,
                                  std::nullopt,
                                  "",
                                  "whole periods at full amplitude; none: enough for 10 s, "
                                  "at least 2"};
inline constexpr Number kFade{"fade",
                              {.lo = 0.0, .hi = 60.0, .unit = "s"},
                              std::nullopt,
                              "raised-cosine fade-in and fade-out; none: period/2"};

// [operator]: every bound required (a class is a claim about the lab's hands, and a default
// would make it silently); tune::OperatorClass::kKeys and kUnits name them.
inline constexpr Number kMaxResonance{
    "max_resonance",
    {.lo = 0.0, .hi = tune::OperatorClass::kMaxResonanceLimitHz, .lo_open = true, .unit = "Hz"}};

}  // namespace schema
}  // namespace hapticd::daemon
