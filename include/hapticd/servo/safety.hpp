// The safety stage of the tick (docs/architecture.md §3.3, §7): takes the coupling's handle
// force and the handle velocity and returns the force to command. In order:
//   fault latch (latched -> zero force, enable = false, in the same tick),
//   non-finite check (-> kFaultNonFinite),
//   velocity limit (fault, or damping on the speed above max_speed_mps),
//   passivity controller, force saturation, soft start scale (so the ramp bounds the force
//   actually commanded), passivity observer.
// A force played open loop (ForceOrigin::open_loop: open_loop_source.hpp) skips the passivity
// controller and the soft start: a source is active by design and brings its own fade-in; the
// observer still counts its energy.
// Only axes < `axes` ever carry force.
//
// Real-time: filter(), raise() never allocate, lock or throw.
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/input/range.hpp"
#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/passivity.hpp"
#include "hapticd/servo/soft_start.hpp"

namespace hapticd::servo {

enum class ForceSaturation {
    vector_norm,  ///< scale the force vector so |F| <= max_force_n (keeps its direction)
    per_axis,     ///< clamp each axis to [-max_force_n, max_force_n]
};

enum class SpeedAction {
    damp,   ///< add -overspeed_damping (|v| - max_speed) v/|v| while too fast
    fault,  ///< latch kFaultOverspeed
};

/// The force and speed limits ([safety] max_force, max_speed): no haptic device pushes 10 kN
/// or moves its handle at 100 m/s (and max_speed sets the encoder-jump threshold, which
/// must stay finite).
inline constexpr input::Range kMaxForceRange{.lo = 0.0, .hi = 1e4, .lo_open = true, .unit = "N"};
inline constexpr input::Range kMaxSpeedRange{
    .lo = 0.0, .hi = 100.0, .lo_open = true, .unit = "m/s"};

struct SafetyLimits {
    double max_force_n = 10.0;  ///< [safety] max_force; also cap it at the device's limit
    ForceSaturation saturation = ForceSaturation::vector_norm;
    double max_speed_mps = 1.0;  ///< [safety] max_speed
    SpeedAction speed_action = SpeedAction::damp;
    double overspeed_damping_n_s_per_m = 50.0;
    /// An encoder step larger than this per period between the two samples is a jump
    /// (kFaultEncoderJump); 0: off.
    double encoder_jump_m = 0.0;
    /// Consecutive read timeouts / dropped samples tolerated before kFaultReadTimeout.
    int read_timeouts_allowed = 2;
    SoftStartSettings soft_start{};
    PassivitySettings passivity{};

    /// Ceres-style: false, with the offending field, its value and the allowed range in
    /// `error`, when a limit is out of range.
    bool is_valid(std::string* error) const;
};

/// Where the tick's force comes from.
enum class ForceOrigin {
    coupling,   ///< the virtual coupling (16) with the environment: every stage applies
    open_loop,  ///< an OpenLoopSource: no passivity controller, no soft start
};

/// What the safety stage decided this tick.
struct SafeForce {
    Vec3 handle_force_n{0.0};  ///< the force to command on the handle, N
    bool enable = false;       ///< false when faulted: the device outputs zero force
    bool saturated = false;    ///< the saturation changed the force
    bool overspeed = false;    ///< the velocity limit acted
    double soft_start_scale = 0.0;
    double passivity_damping_n_s_per_m = 0.0;
};

class SafetySupervisor {
  public:
    SafetySupervisor() = default;
    /// `axes` in 1..kMaxAxes. Throws std::invalid_argument when !limits.is_valid().
    SafetySupervisor(const SafetyLimits& limits, int axes);

    /// Latches `faults` (a Fault mask); the next filter() returns zero force.
    void raise(std::uint32_t faults) noexcept { faults_ |= faults; }
    std::uint32_t faults() const noexcept { return faults_; }
    bool faulted() const noexcept { return faults_ != 0u; }

    /// Clears the latch and restarts the soft start and the passivity observer.
    void reset() noexcept;
    /// Waits for a still handle again before ramping the force up (after arming).
    void restart_soft_start() noexcept { soft_start_.restart(); }

    /// One tick: see the file comment. `period_s` is the time since the previous tick.
    SafeForce filter(const Vec3& handle_force_n, const Vec3& handle_velocity_mps, double period_s,
                     ForceOrigin origin = ForceOrigin::coupling) noexcept;
    /// The passivity observer counts from zero again (the force's origin changed).
    void restart_passivity_observer() noexcept { passivity_.reset(); }

    const SafetyLimits& limits() const noexcept { return limits_; }
    const SoftStart& soft_start() const noexcept { return soft_start_; }
    const PassivityObserver& passivity() const noexcept { return passivity_; }

  private:
    Vec3 mask_axes(Vec3 v) const noexcept;
    Vec3 saturate(const Vec3& force_n, bool& saturated) const noexcept;

    SafetyLimits limits_{};
    int axes_ = 1;
    std::uint32_t faults_ = 0;
    SoftStart soft_start_{};
    PassivityObserver passivity_{};
};

}  // namespace hapticd::servo
