#include "hapticd/servo/safety.hpp"

#include <cmath>
#include <glm/geometric.hpp>
#include <sstream>
#include <stdexcept>

#include "hapticd/servo/coupling.hpp"
#include "hapticd/servo/io.hpp"

namespace hapticd::servo {

namespace {

void require_non_negative(const char* name, double value) {
    if (!(value >= 0.0) || !std::isfinite(value)) {
        std::ostringstream message;
        message << "safety: " << name << " must be a finite number >= 0, got " << value;
        throw std::invalid_argument(message.str());
    }
}

}  // namespace

SafetySupervisor::SafetySupervisor(const SafetyLimits& limits, int axes)
    : limits_(limits), axes_(axes), soft_start_(limits.soft_start), passivity_(limits.passivity) {
    if (axes < 1 || axes > kMaxAxes) {
        throw std::invalid_argument("safety: axes must be in 1.." + std::to_string(kMaxAxes) +
                                    ", got " + std::to_string(axes));
    }
    require_non_negative("max_force_n", limits.max_force_n);
    require_non_negative("max_speed_mps", limits.max_speed_mps);
    require_non_negative("overspeed_damping_n_s_per_m", limits.overspeed_damping_n_s_per_m);
    require_non_negative("encoder_jump_m", limits.encoder_jump_m);
    require_non_negative("soft_start.still_speed_mps", limits.soft_start.still_speed_mps);
    require_non_negative("soft_start.still_time_s", limits.soft_start.still_time_s);
    require_non_negative("soft_start.ramp_time_s", limits.soft_start.ramp_time_s);
    require_non_negative("passivity.max_damping_n_s_per_m", limits.passivity.max_damping_n_s_per_m);
    if (limits.read_timeouts_allowed < 0) {
        throw std::invalid_argument("safety: read_timeouts_allowed must be >= 0, got " +
                                    std::to_string(limits.read_timeouts_allowed));
    }
}

void SafetySupervisor::reset() noexcept {
    faults_ = 0;
    soft_start_.restart();
    passivity_.reset();
}

Vec3 SafetySupervisor::mask_axes(Vec3 v) const noexcept {
    for (int axis = axes_; axis < kMaxAxes; ++axis) v[axis] = 0.0;
    return v;
}

Vec3 SafetySupervisor::saturate(const Vec3& force_n, bool& saturated) const noexcept {
    const double limit = limits_.max_force_n;
    if (limits_.saturation == ForceSaturation::vector_norm) {
        const double norm = glm::length(force_n);
        if (norm > limit) {
            saturated = true;
            return force_n * (limit / norm);
        }
        return force_n;
    }
    Vec3 clamped = force_n;
    for (int axis = 0; axis < kMaxAxes; ++axis) {
        if (std::abs(clamped[axis]) > limit) {
            saturated = true;
            clamped[axis] = std::copysign(limit, clamped[axis]);
        }
    }
    return clamped;
}

SafeForce SafetySupervisor::filter(const Vec3& handle_force_n, const Vec3& handle_velocity_mps,
                                   double period_s) noexcept {
    SafeForce out;
    const Vec3 velocity = mask_axes(handle_velocity_mps);
    Vec3 force = mask_axes(handle_force_n);
    if (!all_finite(force) || !all_finite(velocity)) raise(kFaultNonFinite);

    const double speed = glm::length(velocity);
    if (!faulted() && speed > limits_.max_speed_mps) {
        out.overspeed = true;
        if (limits_.speed_action == SpeedAction::fault) {
            raise(kFaultOverspeed);
        } else {
            // Viscous brake on the excess speed only: continuous at the threshold.
            force -= limits_.overspeed_damping_n_s_per_m * (speed - limits_.max_speed_mps) *
                     (velocity / speed);
        }
    }
    if (faulted()) return out;  // zero force, enable = false, in the tick that raised it

    force = passivity_.control(force, velocity, period_s);
    out.passivity_damping_n_s_per_m = passivity_.damping_n_s_per_m();
    force = saturate(force, out.saturated);
    // The soft start scales the force that would be commanded, after saturation: the ramp
    // bounds what the handle gets (scale x max_force at most), also for a handle that starts
    // inside an object, whose raw force would saturate at once at any scale.
    out.soft_start_scale = soft_start_.update(speed, period_s);
    force *= out.soft_start_scale;
    passivity_.record(force, velocity, period_s);
    out.handle_force_n = force;
    out.enable = true;
    return out;
}

}  // namespace hapticd::servo
