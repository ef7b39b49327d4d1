// The firmware's conversions (firmware/core/hfw_kinematics.c, hfw_f64_bits): force to motor
// duty, the magnetoresistive sensor's flips, quadrature decoding, and counts_per_meter's
// binary64 bits on a compiler whose double is a float.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "hfw_device.h"
#include "hfw_kinematics.h"

namespace hapticd::testing {
namespace {

constexpr std::uint32_t kFullDutyUn = 7'975'089;  // the Hapkit's force at full duty

TEST(FirmwareMotorMap, DutyIsProportionalToForceAndRoundsToTheNearestStep) {
    hfw_motor_map map{};
    hfw_motor_map_init(&map, 256, kFullDutyUn, 1);
    std::mt19937 random(3);
    for (int trial = 0; trial < 20'000; ++trial) {
        const auto force_un = static_cast<std::int32_t>(random() % (2ULL * kFullDutyUn)) -
                              static_cast<std::int32_t>(kFullDutyUn);
        const hfw_duty duty = hfw_force_to_duty(&map, force_un);
        const double exact = 256.0 * std::abs(force_un) / kFullDutyUn;
        // The nearest step, but for the 32-bit fixed point: the force's last 7 bits dropped
        // (128 uN, 0.004 of a 31 mN step) and the multiplier rounded (3e-5 of the duty).
        ASSERT_LE(std::abs(duty.duty - exact), 0.5 + 0.01) << force_un;
        ASSERT_EQ(duty.direction, force_un < 0 ? 1 : 0) << force_un;
    }
    EXPECT_EQ(hfw_force_to_duty(&map, 0).duty, 0);
    EXPECT_EQ(hfw_force_to_duty(&map, static_cast<std::int32_t>(kFullDutyUn)).duty, 256);
    EXPECT_EQ(hfw_force_to_duty(&map, static_cast<std::int32_t>(kFullDutyUn / 2)).duty, 128);
}

TEST(FirmwareMotorMap, SaturatesAtFullDutyWithoutOverflowAndHonoursTheSign) {
    hfw_motor_map map{};
    hfw_motor_map_init(&map, 256, kFullDutyUn, -1);
    const hfw_duty most = hfw_force_to_duty(&map, std::numeric_limits<std::int32_t>::max());
    EXPECT_EQ(most.duty, 256);
    EXPECT_EQ(most.direction, 1) << "force_sign -1: +x needs the direction pin high";
    const hfw_duty least = hfw_force_to_duty(&map, std::numeric_limits<std::int32_t>::min());
    EXPECT_EQ(least.duty, 256);
    EXPECT_EQ(least.direction, 0);
    EXPECT_EQ(hfw_force_to_duty(&map, -1'000'000).direction, 0);
}

/// The sensor's reading at a motor angle (rad): a sawtooth from `low` that falls back by
/// counts_per_flip every half turn.
std::int16_t mr_reading(double angle_rad, int counts_per_flip, int low) {
    const double half_turns = angle_rad / std::numbers::pi;
    const double phase = half_turns - std::floor(half_turns);
    return static_cast<std::int16_t>(low + std::floor(phase * counts_per_flip));
}

TEST(FirmwareMrSensor, UnwrapsFlipsBothWaysOverManyTurns) {
    hfw_mr_sensor sensor{};
    hfw_mr_sensor_init(&sensor, 964, 700);
    const int low = 40;
    // Back and forth over 6 turns of the motor shaft, at up to 40 counts a reading.
    double angle = 0.3;
    const std::int32_t start = hfw_mr_sensor_update(&sensor, mr_reading(angle, 964, low));
    const double step = 40.0 / 964 * std::numbers::pi;
    for (int i = 0; i < 4000; ++i) {
        angle += (i < 1500 ? step : (i < 3500 ? -step : step * 0.3));
        const std::int32_t counts = hfw_mr_sensor_update(&sensor, mr_reading(angle, 964, low));
        const double expected = start + (angle - 0.3) / std::numbers::pi * 964;
        ASSERT_NEAR(counts, expected, 1.0) << "reading " << i << " at " << angle << " rad";
    }
    EXPECT_LT(sensor.flips, -5) << "the run ended several half turns below its start";
}

TEST(FirmwareQuadrature, CountsEdgesBothWaysAndFlagsAMissedOne) {
    const std::uint8_t forward[4] = {0b00, 0b01, 0b11, 0b10};
    int position = 0;
    for (int i = 0; i < 40; ++i) {
        position += hfw_quadrature_step(forward[i % 4], forward[(i + 1) % 4]);
    }
    EXPECT_EQ(position, 40);
    for (int i = 40; i > 0; --i) {
        position += hfw_quadrature_step(forward[i % 4], forward[(i - 1) % 4]);
    }
    EXPECT_EQ(position, 0);
    for (std::uint8_t s = 0; s < 4; ++s) EXPECT_EQ(hfw_quadrature_step(s, s), 0);
    EXPECT_EQ(hfw_quadrature_step(0b00, 0b11), HFW_QUADRATURE_ILLEGAL);
    EXPECT_EQ(hfw_quadrature_step(0b01, 0b10), HFW_QUADRATURE_ILLEGAL);
    EXPECT_EQ(hfw_quadrature_step(0b11, 0b00), HFW_QUADRATURE_ILLEGAL);
    EXPECT_EQ(hfw_quadrature_step(0b10, 0b01), HFW_QUADRATURE_ILLEGAL);
}

TEST(FirmwareF64Bits, EveryKindOfFloatBecomesTheSameDouble) {
    const float specials[] = {0.0f,
                              -0.0f,
                              1.0f,
                              81572.06f,
                              1e5f,
                              -3.5e-20f,
                              std::numeric_limits<float>::min(),
                              std::numeric_limits<float>::denorm_min(),
                              -std::numeric_limits<float>::denorm_min() * 77,
                              std::numeric_limits<float>::max(),
                              std::numeric_limits<float>::infinity(),
                              -std::numeric_limits<float>::infinity()};
    for (const float f : specials) {
        EXPECT_EQ(hfw_f64_bits(f), std::bit_cast<std::uint64_t>(static_cast<double>(f))) << f;
    }
    EXPECT_TRUE(std::isnan(std::bit_cast<double>(hfw_f64_bits(std::nanf("")))));
    std::mt19937 random(5);
    for (int trial = 0; trial < 100'000; ++trial) {
        const auto f = std::bit_cast<float>(static_cast<std::uint32_t>(random()));
        if (std::isnan(f)) continue;
        ASSERT_EQ(hfw_f64_bits(f), std::bit_cast<std::uint64_t>(static_cast<double>(f))) << f;
    }
}

}  // namespace
}  // namespace hapticd::testing
