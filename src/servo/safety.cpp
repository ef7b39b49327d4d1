#include "hapticd/servo/safety.hpp"

#include <cmath>
#include <glm/geometric.hpp>
#include <stdexcept>

#include "hapticd/servo/coupling.hpp"
#include "hapticd/servo/io.hpp"

namespace hapticd::servo {

namespace {

/// A limit that must be finite and >= 0.
bool non_negative(std::string* error, const char* name, double value) {
    if (value >= 0.0 && std::isfinite(value)) return true;
    return input::invalid(
        error, input::out_of_range(std::string("safety.") + name, value, "finite and >= 0"));
}

}  // namespace

bool SafetyLimits::is_valid(std::string* error) const {
    if (!kMaxForceRange.contains(max_force_n)) {
        return input::invalid(
            error, input::out_of_range("safety.max_force_n", max_force_n, kMaxForceRange));
    }
    if (!kMaxSpeedRange.contains(max_speed_mps)) {
        return input::invalid(
            error, input::out_of_range("safety.max_speed_mps", max_speed_mps, kMaxSpeedRange));
    }
    if (!kRampTimeRange.contains(soft_start.ramp_time_s)) {
        return input::invalid(error, input::out_of_range("safety.soft_start.ramp_time_s",
                                                         soft_start.ramp_time_s, kRampTimeRange));
    }
    if (read_timeouts_allowed < 0) {
        return input::invalid(error, input::out_of_range("safety.read_timeouts_allowed",
                                                         read_timeouts_allowed, ">= 0"));
    }
    return non_negative(error, "overspeed_damping_n_s_per_m", overspeed_damping_n_s_per_m) &&
           non_negative(error, "encoder_jump_m", encoder_jump_m) &&
           non_negative(error, "soft_start.still_speed_mps", soft_start.still_speed_mps) &&
           non_negative(error, "soft_start.still_time_s", soft_start.still_time_s) &&
           non_negative(error, "passivity.max_damping_n_s_per_m", passivity.max_damping_n_s_per_m);
}

SafetySupervisor::SafetySupervisor(const SafetyLimits& limits, int axes)
    : limits_(limits), axes_(axes), soft_start_(limits.soft_start), passivity_(limits.passivity) {
    if (axes < 1 || axes > kMaxAxes) {
        input::reject_out_of_range("safety: axes", axes, "1.." + std::to_string(kMaxAxes));
    }
    if (std::string error; !limits.is_valid(&error)) throw std::invalid_argument(error);
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
                                   double period_s, ForceOrigin origin) noexcept {
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

    const bool coupled = origin == ForceOrigin::coupling;
    if (coupled) {
        force = passivity_.control(force, velocity, period_s);
        out.passivity_damping_n_s_per_m = passivity_.damping_n_s_per_m();
    }
    force = saturate(force, out.saturated);
    // The soft start scales the force that would be commanded, after saturation: the ramp
    // bounds what the handle gets (scale x max_force at most), also for a handle that starts
    // inside an object, whose raw force would saturate at once at any scale.
    out.soft_start_scale = coupled ? soft_start_.update(speed, period_s) : 1.0;
    force *= out.soft_start_scale;
    passivity_.record(force, velocity, period_s);
    out.handle_force_n = force;
    out.enable = true;
    return out;
}

}  // namespace hapticd::servo
