// The paddle that hapticd-avr-sim puts around the emulated MCU (tools/avr-sim/paddle_plant):
// its dynamics against closed forms, its motor against the firmware's kinematics, and its
// sensors' signals.
#include "paddle_plant.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

namespace hapticd::testing {
namespace {

using avr_sim::MotorPins;
using avr_sim::PaddleConfig;
using avr_sim::PaddlePlant;

constexpr double kStepS = 4e-6;

void run(PaddlePlant& plant, double seconds, MotorPins pins) {
    const auto steps = static_cast<int>(std::lround(seconds / kStepS));
    for (int i = 0; i < steps; ++i) plant.step(kStepS, pins);
}

TEST(FilPaddlePlant, TheMotorsForceFollowsDutyDirectionAndTheKinematics) {
    PaddleConfig config;
    PaddlePlant plant(config);
    // 0.03 N m at the motor, through r_p/r_s and r_h: 7.975 N on the handle (hapkit.h).
    EXPECT_NEAR(plant.full_duty_force_n(), 7.975088923626061, 1e-12);
    plant.step(kStepS, {0.5, false});
    EXPECT_NEAR(plant.motor_force_n(), 0.5 * 7.975088923626061, 1e-12);
    plant.step(kStepS, {0.25, true});
    EXPECT_NEAR(plant.motor_force_n(), -0.25 * 7.975088923626061, 1e-12);
    config.force_sign = -1;
    PaddlePlant reversed(config);
    reversed.step(kStepS, {0.25, true});
    EXPECT_NEAR(reversed.motor_force_n(), 0.25 * 7.975088923626061, 1e-12);
}

TEST(FilPaddlePlant, AConstantForceAgainstViscousDampingReachesItsClosedForm) {
    PaddleConfig config;
    config.mass_kg = 0.05;
    config.damping_n_s_per_m = 0.5;
    PaddlePlant plant(config);
    const MotorPins pins{0.1, false};
    run(plant, 0.2, pins);
    const double force = 0.1 * plant.full_duty_force_n();
    const double tau = config.mass_kg / config.damping_n_s_per_m;
    const double t = plant.time_s();
    const double v = force / config.damping_n_s_per_m * (1.0 - std::exp(-t / tau));
    const double x = force / config.damping_n_s_per_m * (t - tau * (1.0 - std::exp(-t / tau)));
    EXPECT_NEAR(plant.velocity_mps(), v, 1e-4 * v);
    EXPECT_NEAR(plant.position_m(), x, 1e-4 * x);
}

TEST(FilPaddlePlant, DryFrictionHoldsBelowItsForceAndStopsTheHandle) {
    PaddleConfig config;
    config.coulomb_n = 0.2;
    config.damping_n_s_per_m = 0.0;
    PaddlePlant plant(config);
    const double below = 0.19 / plant.full_duty_force_n();
    run(plant, 0.1, {below, false});
    EXPECT_EQ(plant.position_m(), 0.0);
    EXPECT_EQ(plant.velocity_mps(), 0.0);
    // Above it, the net force is 0.3 - 0.2 N.
    run(plant, 0.1, {0.3 / plant.full_duty_force_n(), false});
    EXPECT_NEAR(plant.velocity_mps(), 0.1 / config.mass_kg * 0.1, 1e-3);
    // Released, friction decelerates it at 0.2 N / m and it stays stopped.
    const double v = plant.velocity_mps();
    run(plant, 0.5, {0.0, false});
    EXPECT_EQ(plant.velocity_mps(), 0.0);
    EXPECT_GT(plant.time_s(), v / (0.2 / config.mass_kg));
}

TEST(FilPaddlePlant, AHandSpringHoldsTheHandleWhereThePushBalancesIt) {
    PaddleConfig config;
    config.human.kind = avr_sim::PaddleOperator::Kind::hand;
    config.human.mass_kg = 0.1;
    config.human.stiffness_n_per_m = 200.0;
    config.human.damping_n_s_per_m = 5.0;
    config.human.push_n = 1.0;
    config.human.push_duration_s = 10.0;
    PaddlePlant plant(config);
    run(plant, 2.0, {0.0, false});
    EXPECT_NEAR(plant.position_m(), 1.0 / 200.0, 1e-6);
}

TEST(FilPaddlePlant, TheMrSensorsSawtoothFlipsEveryHalfTurn) {
    PaddleConfig config;
    config.mr_phase_rad = 0.0;
    PaddlePlant plant(config);
    EXPECT_EQ(plant.mr_adc_counts(), config.mr_low_counts);
    // Just short of a half turn of the motor: the top of the sawtooth; just past: the bottom.
    const double half_turn_m = std::numbers::pi * config.kinematics.handle_m_per_motor_rad();
    const double speed = half_turn_m / 0.1;
    PaddleConfig moving = config;
    moving.damping_n_s_per_m = 0.0;
    PaddlePlant turning(moving);
    int highest = 0;
    bool flipped = false;
    int last = turning.mr_adc_counts();
    // Drive it at about constant speed with a damper-free push: watch one flip.
    for (int i = 0; i < 200'000 && !flipped; ++i) {
        turning.step(kStepS, {turning.velocity_mps() < speed ? 0.05 : 0.0, false});
        const int now = turning.mr_adc_counts();
        highest = std::max(highest, now);
        flipped = now < last - 700;
        last = now;
    }
    EXPECT_TRUE(flipped);
    EXPECT_GE(highest, config.mr_low_counts + config.mr_counts_per_flip - 3);
    EXPECT_NEAR(turning.motor_angle_rad(), std::numbers::pi, 0.01);
    EXPECT_NEAR(plant.mr_counts_per_meter(), 81572.06200906535, 1e-6);
}

TEST(FilPaddlePlant, TheEncodersChannelsAreGrayCodeOverTheTurn) {
    PaddleConfig config;
    config.encoder_counts_per_rev = 8;
    config.damping_n_s_per_m = 0.0;
    PaddlePlant plant(config);
    int changes = 0;
    std::uint8_t last = plant.encoder_channels();
    while (plant.motor_angle_rad() < 2.0 * std::numbers::pi) {
        plant.step(kStepS, {0.01, false});
        const std::uint8_t now = plant.encoder_channels();
        if (now != last) {
            EXPECT_EQ(std::popcount(static_cast<unsigned>(now ^ last)), 1) << "not Gray code";
            ++changes;
        }
        last = now;
    }
    EXPECT_EQ(changes, 8);
}

}  // namespace
}  // namespace hapticd::testing
