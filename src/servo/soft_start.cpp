#include "hapticd/servo/soft_start.hpp"

namespace hapticd::servo {

void SoftStart::restart() noexcept {
    phase_ = Phase::waiting_for_still;
    still_for_s_ = 0.0;
    ramp_elapsed_s_ = 0.0;
    scale_ = 0.0;
}

double SoftStart::update(double speed_mps, double period_s) noexcept {
    // still_time_s = 0: no wait; ramp_time_s = 0: a step (both 0: soft start off).
    if (phase_ == Phase::waiting_for_still && settings_.still_time_s <= 0.0) {
        phase_ = Phase::ramping;
        ramp_elapsed_s_ = 0.0;
    }
    switch (phase_) {
        case Phase::waiting_for_still:
            // Any motion (or a non-finite speed) restarts the stillness timer.
            if (speed_mps < settings_.still_speed_mps) {
                still_for_s_ += period_s;
            } else {
                still_for_s_ = 0.0;
            }
            // Half a period of slack: the sum of n periods may round just below n T.
            if (still_for_s_ + 0.5 * period_s >= settings_.still_time_s) {
                phase_ = Phase::ramping;
                ramp_elapsed_s_ = 0.0;
            }
            scale_ = 0.0;
            break;
        case Phase::ramping:
            // The first ramping tick commands T/ramp_time, the last one 1.
            ramp_elapsed_s_ += period_s;
            scale_ = settings_.ramp_time_s > 0.0 ? ramp_elapsed_s_ / settings_.ramp_time_s : 1.0;
            if (ramp_elapsed_s_ + 0.5 * period_s >= settings_.ramp_time_s) {
                scale_ = 1.0;
                phase_ = Phase::active;
            }
            break;
        case Phase::active:
            scale_ = 1.0;
            break;
    }
    return scale_;
}

}  // namespace hapticd::servo
