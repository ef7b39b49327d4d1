// What the seeded fault campaigns share (docs/reliability.md): the scenario, the servo
// configuration, and the checks that hold whatever the faults were.
// tests/hil/fault_campaign_test.cpp injects faults at the servo's Device interface against the
// simulated device; tests/device/serial/serial_fault_campaign_test.cpp puts them on the wire
// between the device emulator and the serial plugin.
//
// The scenario: a stiff grasp pressed into a 2e4 N/m wall through the coupling (3600 N/m),
// max_force 8 N, link recovery on or off (settle 30 ms, timeout 250 ms), in lockstep, the
// loop paced by the device (ServoLoop::run), as the daemon runs a lockstep device.
//
// The checks are gtest ASSERTs: a broken invariant is a fatal failure of the helper; the
// caller tests HasFatalFailure() (the SCOPED_TRACE it set names the seed).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <vector>

#include "hapticd/device/sim/sim_config.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/servo/servo_loop.hpp"

namespace hapticd::testing::campaign {

constexpr double kMaxForceN = 8.0;
constexpr double kCountsPerMeter = 1e5;
constexpr double kPeriodS = 1e-3;
constexpr std::int64_t kSettleTicks = 30;    ///< link_recovery.settle_s
constexpr std::int64_t kTimeoutTicks = 250;  ///< link_recovery.timeout_s

/// The pen display held in a stiff grasp that pushes 8 mm into the wall at x = 0.
inline device::sim::SimConfig sim_config() {
    device::sim::SimConfig c;
    c.clock = device::sim::SimClock::lockstep;
    c.mass_kg = 0.1;
    c.damping_n_s_per_m = 2.0;
    c.counts_per_meter = kCountsPerMeter;
    c.force_limit_n = 20.0;
    c.initial_position_m[0] = -0.002;
    c.human[0].family = device::sim::HumanFamily::stiff_grasp;
    c.human[0].hand_mass_kg = 0.3;
    c.human[0].hand_stiffness_n_per_m = 500.0;
    c.human[0].hand_damping_n_s_per_m = 5.0;
    c.human[0].push = {
        .from_m = -0.002, .to_m = 0.006, .start_s = 0.05, .ramp_s = 0.2, .hold_s = 5.0};
    return c;
}

inline servo::ServoConfig servo_config(bool reconnect) {
    servo::ServoConfig c;
    c.rate_hz = 1.0 / kPeriodS;
    c.counts_per_meter = kCountsPerMeter;
    c.coupling = {.stiffness_n_per_m = 3600.0, .damping_n_s_per_m = 0.0};
    c.safety.max_force_n = kMaxForceN;
    c.safety.max_speed_mps = 1.0;
    c.safety.encoder_jump_m = 10.0 * 1.0 * kPeriodS;
    c.safety.soft_start = {.still_speed_mps = 0.02, .still_time_s = 0.01, .ramp_time_s = 0.05};
    c.realtime.mode = servo::RealtimeMode::off;
    c.device_paces_loop = true;
    c.link_recovery = {.enabled = reconnect,
                       .settle_s = kSettleTicks * kPeriodS,
                       .timeout_s = kTimeoutTicks * kPeriodS};
    return c;
}

inline env::Scene wall_scene() {
    return env::parse_scene(
        "[scene]\nname = \"wall\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\nstiffness = 2e4\n"
        "damping = 5.0\n",
        "campaign", 1);
}

/// Every record of a run, in order (the ring drained after the loop is gone).
inline std::vector<servo::TelemetryRecord> drain(servo::TelemetryRing& ring) {
    std::vector<servo::TelemetryRecord> records;
    servo::TelemetryRecord r;
    while (ring.try_pop(r)) records.push_back(r);
    return records;
}

/// On every tick: every value finite, |F| <= max_force, zero force whenever a fault is
/// latched (which includes the tick that detects it) and on a tick whose interval is unknown.
inline void check_every_tick(const std::vector<servo::TelemetryRecord>& records) {
    for (std::size_t n = 0; n < records.size(); ++n) {
        const servo::TelemetryRecord& rec = records[n];
        const double f = rec.f_n[0];
        ASSERT_TRUE(std::isfinite(f) && std::isfinite(rec.x_m[0]) && std::isfinite(rec.v_mps[0]))
            << "tick " << n;
        ASSERT_LE(std::abs(f), kMaxForceN + 1e-9) << "tick " << n;
        if (rec.faults != 0u) {
            ASSERT_EQ(f, 0.0) << "tick " << n << " faults " << rec.faults;
        }
        if ((rec.flags & servo::kFlagIntervalUnknown) != 0u) {
            ASSERT_EQ(f, 0.0) << "tick " << n;
        }
    }
}

/// On every sequence: the outcome the configuration says. Non-link faults end the run;
/// without reconnect any fault ends it; with reconnect each latch of link faults clears
/// only after a whole settle time of good samples and within the timeout, or the run gives
/// up once the timeout has run out.
inline void check_outcome(const std::vector<servo::TelemetryRecord>& records, servo::RunExit exit,
                          std::uint32_t faults_seen, bool reconnect) {
    const bool non_link_fault = (faults_seen & ~servo::kLinkFaults) != 0u;
    if (non_link_fault) {
        ASSERT_EQ(exit, servo::RunExit::fault);
    }
    if (!reconnect && faults_seen != 0u) {
        ASSERT_EQ(exit, servo::RunExit::fault);
    }
    if (reconnect && !non_link_fault && faults_seen != 0u) {
        // Link faults only. Each latch either clears after the device was good for the whole
        // settle time (the tick flagged link-recovered), within the timeout, or is still held
        // at the end: then the run gave up if the timeout ran out, and ran on otherwise. (A
        // fault in the tick after a recovery is a new latch.)
        std::size_t n = 0;
        while (n < records.size()) {
            if (records[n].faults == 0u) {
                ++n;
                continue;
            }
            const std::size_t start = n;
            bool recovered = false;
            while (n < records.size() && records[n].faults != 0u && !recovered) {
                recovered = (records[n].flags & servo::kFlagLinkRecovered) != 0u;
                ++n;
            }
            const std::size_t last = n - 1;
            const auto held = static_cast<std::int64_t>(last - start);
            if (recovered || n < records.size()) {
                ASSERT_NE(records[last].flags & servo::kFlagLinkRecovered, 0u) << "tick " << last;
                ASSERT_LE(held, kTimeoutTicks) << "latched at " << start;
                for (std::int64_t k = 0; k < kSettleTicks; ++k) {
                    const servo::TelemetryRecord& good =
                        records[last - static_cast<std::size_t>(k)];
                    ASSERT_EQ(good.flags & servo::kFlagNoSample, 0u) << "recovered over a bad tick";
                }
            } else if (exit == servo::RunExit::fault) {
                ASSERT_GE(held, kTimeoutTicks - 1) << "gave up early, latched at " << start;
            } else {
                ASSERT_LT(held, kTimeoutTicks + 1) << "did not give up, latched at " << start;
            }
        }
    }
    if (exit == servo::RunExit::fault) {
        ASSERT_NE(records.back().faults, 0u);
    }
}

/// An unsigned number from the environment variable `name`, if it is set.
inline std::optional<std::uint64_t> env_count(const char* name) {
    const char* value = std::getenv(name);
    if (value == nullptr) return std::nullopt;
    return std::strtoull(value, nullptr, 10);
}

}  // namespace hapticd::testing::campaign
