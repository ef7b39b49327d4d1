// The Hapkit paddle around the emulated ATmega328P (docs/firmware.md, "The harness"): the
// handle's dynamics, the motor as the driver's duty and direction pins make it push, the
// magnetoresistive sensor's sawtooth on A2 (or a quadrature encoder's channels), and an
// operator. No simavr here: hapticd-avr-sim feeds it the pins and time, and the unit tests
// drive it alone.
#pragma once

#include <cstdint>

namespace hapticd::avr_sim {

/// A capstan of radius r_p on the motor shaft turns a sector of radius r_s; the handle is
/// r_h long. Defaults: the Hapkit course's (firmware/config/hapkit.h).
struct PaddleKinematics {
    double handle_radius_m = 0.065659;
    double sector_radius_m = 0.073152;
    double capstan_radius_m = 0.004191;
    /// Handle travel per radian of the motor shaft: r_h r_p / r_s.
    double handle_m_per_motor_rad() const {
        return handle_radius_m * capstan_radius_m / sector_radius_m;
    }
};

/// How the operator holds the handle.
struct PaddleOperator {
    enum class Kind { hands_off, hand };
    Kind kind = Kind::hands_off;
    /// A hand: its mass moves with the handle; a spring and damper pull it to rest_m.
    double mass_kg = 0.0;
    double stiffness_n_per_m = 0.0;
    double damping_n_s_per_m = 0.0;
    double rest_m = 0.0;
    /// A push: push_n on the handle from push_start_s for push_duration_s (with any kind).
    double push_n = 0.0;
    double push_start_s = 0.0;
    double push_duration_s = 0.0;
};

struct PaddleConfig {
    double mass_kg = 0.05;            ///< the handle's mass, reflected to the handle
    double damping_n_s_per_m = 0.5;   ///< viscous
    double coulomb_n = 0.0;           ///< dry friction: the force it takes to move the handle
    double initial_position_m = 0.0;  ///< where the handle is at power-up (the firmware's zero)
    double torque_at_full_duty_nm = 0.03;  ///< on the motor shaft
    int force_sign = 1;     ///< +1: duty with the direction pin low pushes towards +x
    int position_sign = 1;  ///< +1: the motor angle (and the counts) grow towards +x
    PaddleKinematics kinematics;
    /// The MR sensor: ADC counts over each half turn of the motor shaft, from low_counts.
    int mr_counts_per_flip = 964;
    int mr_low_counts = 30;
    /// The motor angle (rad) at power-up, where the sensor's sawtooth starts.
    double mr_phase_rad = 0.5;
    /// A quadrature encoder instead: counts per turn of the motor shaft after x4 decoding.
    int encoder_counts_per_rev = 2000;
    PaddleOperator human;
};

/// What drives the motor: the PWM's share of a period (0..1) and the direction pin.
struct MotorPins {
    double duty = 0.0;
    bool direction_high = false;
};

class PaddlePlant {
  public:
    explicit PaddlePlant(const PaddleConfig& config);

    /// Advances dt_s with the pins held (semi-implicit Euler; dry friction sticks the handle
    /// when the other forces cannot move it).
    void step(double dt_s, MotorPins pins);

    double time_s() const { return time_s_; }
    double position_m() const { return position_m_; }
    double velocity_mps() const { return velocity_mps_; }
    /// The motor's force on the handle at the last step (N, along +x).
    double motor_force_n() const { return motor_force_n_; }
    /// The force on the handle at 100 % duty (N).
    double full_duty_force_n() const;
    /// The motor shaft's angle from its power-up angle (rad).
    double motor_angle_rad() const;
    /// The MR sensor's reading now, in ADC counts (0..1023).
    int mr_adc_counts() const;
    /// The quadrature channels now (bit 1: A, bit 0: B).
    std::uint8_t encoder_channels() const;
    /// Counts per metre of handle travel as the firmware reports them.
    double mr_counts_per_meter() const;

    const PaddleConfig& config() const { return config_; }

  private:
    double motor_force(MotorPins pins) const;

    PaddleConfig config_;
    double time_s_ = 0.0;
    double position_m_ = 0.0;
    double velocity_mps_ = 0.0;
    double motor_force_n_ = 0.0;
};

}  // namespace hapticd::avr_sim
