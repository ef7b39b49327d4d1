// Soft start (docs/architecture.md §7.3): no force until the handle has been still for a
// while, then a linear ramp of the force scale from 0 to 1. A person who grabs a handle
// that starts inside a wall is not thrown by a full-stiffness step.
#pragma once

#include "hapticd/input/range.hpp"

namespace hapticd::servo {

/// The force ramp's length ([safety] soft_start_ramp).
inline constexpr input::Range kRampTimeRange{.lo = 0.0, .hi = 10.0, .unit = "s"};

struct SoftStartSettings {
    double still_speed_mps = 0.02;  ///< |v_d| below this counts as still
    double still_time_s = 0.2;      ///< how long the handle must stay still before the ramp
    double ramp_time_s = 0.5;       ///< 0 -> 1 over this long; 0: a step
};

class SoftStart {
  public:
    enum class Phase { waiting_for_still, ramping, active };

    SoftStart() = default;
    explicit SoftStart(const SoftStartSettings& settings) : settings_(settings) {}

    /// Back to waiting for a still handle (after arming or a fault reset).
    void restart() noexcept;

    /// One tick of `period_s` with the handle at `speed_mps` (|v_d|); returns the force
    /// scale in [0, 1] to apply this tick.
    double update(double speed_mps, double period_s) noexcept;

    Phase phase() const noexcept { return phase_; }
    double scale() const noexcept { return scale_; }

  private:
    SoftStartSettings settings_{};
    Phase phase_ = Phase::waiting_for_still;
    double still_for_s_ = 0.0;
    double ramp_elapsed_s_ = 0.0;
    double scale_ = 0.0;
};

}  // namespace hapticd::servo
