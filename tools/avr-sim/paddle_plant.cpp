#include "paddle_plant.hpp"

#include <cmath>
#include <numbers>

namespace hapticd::avr_sim {

PaddlePlant::PaddlePlant(const PaddleConfig& config)
    : config_(config), position_m_(config.initial_position_m) {}

double PaddlePlant::full_duty_force_n() const {
    return config_.torque_at_full_duty_nm / config_.kinematics.handle_m_per_motor_rad();
}

double PaddlePlant::motor_force(MotorPins pins) const {
    const double direction = pins.direction_high ? -1.0 : 1.0;
    return direction * config_.force_sign * pins.duty * full_duty_force_n();
}

void PaddlePlant::step(double dt_s, MotorPins pins) {
    const PaddleOperator& human = config_.human;
    motor_force_n_ = motor_force(pins);
    double force_n = motor_force_n_ - config_.damping_n_s_per_m * velocity_mps_;
    double mass_kg = config_.mass_kg;
    if (human.kind == PaddleOperator::Kind::hand) {
        mass_kg += human.mass_kg;
        force_n -= human.stiffness_n_per_m * (position_m_ - human.rest_m) +
                   human.damping_n_s_per_m * velocity_mps_;
    }
    if (time_s_ >= human.push_start_s && time_s_ < human.push_start_s + human.push_duration_s) {
        force_n += human.push_n;
    }
    // Dry friction: at rest it holds the handle against up to coulomb_n; moving, it opposes
    // the motion, and where the velocity would cross zero the handle stops (the next step
    // decides from rest whether it moves again).
    const double coulomb = config_.coulomb_n;
    if (coulomb > 0.0) {
        if (velocity_mps_ == 0.0 && std::abs(force_n) <= coulomb) {
            time_s_ += dt_s;
            return;
        }
        force_n -= std::copysign(coulomb, velocity_mps_ != 0.0 ? velocity_mps_ : force_n);
    }
    const double velocity = velocity_mps_ + force_n / mass_kg * dt_s;
    const bool reversed = coulomb > 0.0 && velocity * velocity_mps_ < 0.0;
    velocity_mps_ = reversed ? 0.0 : velocity;
    position_m_ += velocity_mps_ * dt_s;
    time_s_ += dt_s;
}

double PaddlePlant::motor_angle_rad() const {
    return config_.position_sign * (position_m_ - config_.initial_position_m) /
           config_.kinematics.handle_m_per_motor_rad();
}

int PaddlePlant::mr_adc_counts() const {
    const double half_turns = (motor_angle_rad() + config_.mr_phase_rad) / std::numbers::pi;
    const double phase = half_turns - std::floor(half_turns);
    return config_.mr_low_counts + static_cast<int>(std::floor(phase * config_.mr_counts_per_flip));
}

std::uint8_t PaddlePlant::encoder_channels() const {
    const double counts =
        std::floor(motor_angle_rad() / (2.0 * std::numbers::pi) * config_.encoder_counts_per_rev);
    const auto quarter = static_cast<std::int64_t>(counts) & 3;
    static constexpr std::uint8_t kGray[4] = {0b00, 0b01, 0b11, 0b10};
    return kGray[quarter];
}

double PaddlePlant::mr_counts_per_meter() const {
    return config_.mr_counts_per_flip /
           (std::numbers::pi * config_.kinematics.handle_m_per_motor_rad());
}

}  // namespace hapticd::avr_sim
