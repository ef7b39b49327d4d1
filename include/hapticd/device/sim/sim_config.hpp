// Configuration of the simulated device (the `sim` plugin): the validated form of the
// [device.sim] TOML table. The schema, defaults and ranges are documented in docs/sim-device.md;
// parse_sim_config() is the only place that reads TOML.
//
// Units: SI throughout (kg, N s/m, N/m, N, m, s); encoder resolution in counts per metre.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticd/device/device.hpp"

namespace hapticd::device::sim {

enum class SimClock {
    lockstep,  ///< virtual time: each write() advances the physics by exactly one period
    realtime,  ///< the physics follows CLOCK_MONOTONIC
};

/// The passive human operator families of hapticd::tune::OperatorFamily (exact_model.hpp).
enum class HumanFamily { hands_off, heavy_hand, stiff_grasp, two_mass_grasp, multi_mode_grasp };

/// A multi-mode grasp's absorbers: at most this many (the sim's plant is fixed-size).
inline constexpr int kMaxOperatorModes = 8;

/// A multi-mode grasp's absorber: handle --(stiffness, damping)-- mass.
struct OperatorMode {
    double mass_kg = 0.0;            ///< > 0
    double stiffness_n_per_m = 0.0;  ///< > 0
    double damping_n_s_per_m = 0.0;  ///< >= 0
};

/// The hand's set-point x_s(t) for the grasps (stiff grasp: the spring's rest point; two-mass
/// grasp: the arm's). A trapezoid: x_from until `start_s`, a linear ramp to x_to over `ramp_s`,
/// hold for `hold_s`, a linear ramp back over `ramp_s`, then x_from. With ramp_s = 0 and
/// hold_s = 0 (the default) the set-point is fixed at x_from.
struct PushProfile {
    double from_m = 0.0;
    double to_m = 0.0;
    double start_s = 0.0;
    double ramp_s = 0.0;
    double hold_s = 0.0;

    bool is_fixed() const { return ramp_s == 0.0 && hold_s == 0.0; }
    /// x_s(t), continuous and piecewise linear in t.
    double set_point_m(double t_s) const noexcept;
};

/// A passive operator attached to one axis (see docs/sim-device.md for the mechanics).
/// The fields a family does not use are zero.
struct HumanModel {
    HumanFamily family = HumanFamily::hands_off;
    double hand_mass_kg = 0.0;            ///< heavy hand, stiff, multi-mode (>= 0); two-mass (> 0)
    double hand_damping_n_s_per_m = 0.0;  ///< heavy hand (to ground); stiff, multi-mode (to x_s)
    double hand_stiffness_n_per_m = 0.0;  ///< stiff grasp, multi-mode: handle to x_s
    double skin_stiffness_n_per_m = 0.0;  ///< two-mass grasp: handle to hand
    double skin_damping_n_s_per_m = 0.0;  ///< two-mass grasp: handle to hand
    double arm_stiffness_n_per_m = 0.0;   ///< two-mass grasp: hand to x_s
    double arm_damping_n_s_per_m = 0.0;   ///< two-mass grasp: hand to x_s
    std::array<OperatorMode, kMaxOperatorModes> modes{};  ///< multi-mode grasp: the absorbers
    int mode_count = 0;                                   ///< multi-mode grasp: 1..8
    /// Set-point x_s(t); used by the stiff, two-mass and multi-mode grasps. Its from_m defaults to
    /// the axis's initial position, so a grasp starts at rest.
    PushProfile push;
};

/// Injected faults, deterministic for a given seed. Times are device time since open(), s;
/// an event at time t hits the first sample whose device time is >= t. A negative time
/// (the default) disables the fault.
struct FaultConfig {
    double disconnect_at_s = -1.0;  ///< from then on read/write return disconnected
    double stale_at_s = -1.0;       ///< encoder counts freeze (kStatusStale) ...
    double stale_for_s = -1.0;      ///< ... for this long; < 0: for ever
    double jump_at_s = -1.0;        ///< encoder counts jump by jump_counts (kStatusJump) ...
    std::int64_t jump_counts = 0;   ///< ... and keep the offset afterwards
    int jump_axis = 0;
    std::vector<double> drop_at_s;  ///< replies lost (read returns timeout, kStatusDropped)
    double drop_probability = 0.0;  ///< per sample, 0..1
    std::vector<double> late_at_s;  ///< replies late (kStatusLate)
    double late_probability = 0.0;  ///< per sample, 0..1
    double late_by_s = 0.0;         ///< realtime clock: how late; 0 -> half a period
    std::uint64_t seed = 1;

    bool any() const;
};

struct SimConfig {
    int axes = 1;
    double rate_hz = 1000.0;
    double mass_kg = 0.1;            ///< m in (10)
    double damping_n_s_per_m = 2.0;  ///< b in (10)
    double counts_per_meter = 1e5;   ///< encoder resolution; counts = floor(x cpm)
    double force_limit_n = 20.0;     ///< commands are clamped to +-this
    double coulomb_n = 0.0;          ///< Coulomb friction magnitude; 0: none
    SimClock clock = SimClock::realtime;
    /// Loop delay D, s: from the encoder sample at t = nT to the force computed from it
    /// taking effect (beyond the zero-order hold); >= 0 and < 10 periods
    /// (command_pipeline.hpp).
    double delay_s = 0.0;
    std::array<double, kMaxAxes> initial_position_m{};
    std::array<HumanModel, kMaxAxes> human{};  ///< per axis
    FaultConfig faults;

    double period_s() const { return 1.0 / rate_hz; }
};

/// Validates DeviceConfig (axes, rate) and the [device.sim] table text in
/// config.plugin_table_toml: the table's contents as a TOML document (its keys at top level,
/// its sub-tables as [human] / [[human]] / [faults]). config.lockstep forces the lockstep
/// clock. Throws std::runtime_error naming config.source, the key (device.sim.<key>), the
/// value and the allowed range; unknown keys are errors.
SimConfig parse_sim_config(const DeviceConfig& config);

}  // namespace hapticd::device::sim
