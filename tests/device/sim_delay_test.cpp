// The simulated device's loop delay ([device.sim] delay, command_pipeline.hpp): zero delay
// is the sim as it was, bit for bit; whole periods shift the response by whole ticks; a
// fractional delay is the exact solution of (10) under the shifted zero-order hold; and the
// commands in flight land, or do not, as docs/sim-device.md says.
#include <gtest/gtest.h>
#include <time.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "hapticd/device/sim/command_pipeline.hpp"
#include "hapticd/device/sim/sim_device.hpp"

namespace hapticd::device::sim {
namespace {

constexpr double kPeriodS = 1e-3;

SimConfig lockstep_config(double delay_s = 0.0) {
    SimConfig c;
    c.rate_hz = 1.0 / kPeriodS;
    c.clock = SimClock::lockstep;
    c.delay_s = delay_s;
    return c;
}

Command force(double f0, double f1 = 0.0, double f2 = 0.0) {
    Command c;
    c.enable = true;
    c.force_n = {f0, f1, f2};
    return c;
}

HumanModel heavy_hand(double mh, double bh) {
    HumanModel h;
    h.family = HumanFamily::heavy_hand;
    h.hand_mass_kg = mh;
    h.hand_damping_n_s_per_m = bh;
    return h;
}

// ---------------------------------------------------------------------------------------
// delay = 0 is the sim of commit cb6c389 (before the delay existed), bit for bit.

/// FNV-1a over bytes.
struct Fnv {
    std::uint64_t hash = 1469598103934665603ull;
    template <typename T>
    void add(const T& value) {
        unsigned char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        for (const unsigned char b : bytes) {
            hash ^= b;
            hash *= 1099511628211ull;
        }
    }
};

/// Three axes, every operator family but hands-off, pushes, Coulomb friction, random drops
/// and late replies, a stale stretch and an encoder jump.
SimConfig busy_lockstep_config() {
    SimConfig c = lockstep_config();
    c.axes = 3;
    c.coulomb_n = 0.05;
    c.initial_position_m = {0.001, -0.002, 0.0};
    c.human[0].family = HumanFamily::stiff_grasp;
    c.human[0].hand_mass_kg = 0.3;
    c.human[0].hand_stiffness_n_per_m = 500.0;
    c.human[0].hand_damping_n_s_per_m = 2.0;
    c.human[0].push = PushProfile{0.001, 0.011, 0.1, 0.2, 0.3};
    c.human[1].family = HumanFamily::two_mass_grasp;
    c.human[1].hand_mass_kg = 0.3;
    c.human[1].skin_stiffness_n_per_m = 3000.0;
    c.human[1].skin_damping_n_s_per_m = 1.0;
    c.human[1].arm_stiffness_n_per_m = 100.0;
    c.human[1].arm_damping_n_s_per_m = 5.0;
    c.human[1].push = PushProfile{-0.002, 0.008, 0.05, 0.1, 0.2};
    c.human[2] = heavy_hand(0.5, 1.0);
    c.faults.drop_probability = 0.02;
    c.faults.late_probability = 0.02;
    c.faults.stale_at_s = 0.3;
    c.faults.stale_for_s = 0.01;
    c.faults.jump_at_s = 0.5;
    c.faults.jump_counts = 7;
    c.faults.jump_axis = 1;
    c.faults.seed = 42;
    return c;
}

/// A closed loop (a spring-damper on the counts, an open-loop wiggle, now and then a
/// disabled, a clamped and a non-finite command) for `ticks` ticks, hashing every result,
/// sample, plant state and held force.
std::uint64_t trajectory_hash(const SimConfig& config, int ticks) {
    SimDevice dev;
    dev.open(config);
    Fnv fnv;
    Sample s;
    std::int64_t previous = 0;
    for (int n = 0; n < ticks; ++n) {
        const IoResult r = dev.read(s);
        fnv.add(static_cast<int>(r));
        fnv.add(s.sequence);
        fnv.add(s.device_time_s);
        fnv.add(s.status);
        for (int i = 0; i < 3; ++i) fnv.add(s.encoder_counts[i]);
        Command cmd;
        cmd.enable = n % 97 != 13;
        for (int i = 0; i < 3; ++i) {
            const double x = static_cast<double>(s.encoder_counts[i]) * 1e-5;
            cmd.force_n[i] = -800.0 * x -
                             0.8 * static_cast<double>(s.encoder_counts[i] - previous) +
                             3.0 * std::sin(0.013 * n + i) + (n % 211 == 5 ? 40.0 : 0.0);
        }
        previous = s.encoder_counts[0];
        if (n == 777) cmd.force_n[1] = std::nan("");
        fnv.add(static_cast<int>(dev.write(cmd)));
        for (int i = 0; i < 3; ++i) {
            const AxisPlant::State& st = dev.plant(i).state();
            fnv.add(st.position_m);
            fnv.add(st.velocity_mps);
            fnv.add(st.mass_position_m[0]);
            fnv.add(st.mass_velocity_mps[0]);
            fnv.add(st.set_point_m);
            fnv.add(dev.held_force_n()[i]);
        }
    }
    return fnv.hash;
}

// The hashes were computed by this same function compiled against the sources of commit
// cb6c389 (gcc 12 -O0 and -O2, clang 14 -O2 agree: nothing here depends on contraction or
// vectorisation choices, x86-64 has no FMA by default). A change in any bit of any sample,
// state or force of the 3000 ticks changes them. The second was computed again when the
// plant became a network of masses of run-time size (axis_plant.hpp, for the multi-mode
// grasp): Eigen's products of that size sum in another order, which moved the last bits of
// some samples of the friction-free run (the two plants' trajectories agree to 4e-13
// relative); gcc -O0, -O2 and clang -O1, -O2 agree on the new one. All three were computed
// again (gcc 12 -O2) when the sim's clock became n / rate, the double nearest each tick's
// time (for the telemetry's short decimals), where it had been n * (1/rate): the times, and
// the push profiles' set points that depend on them, moved in their last bits.
TEST(SimDelay, ZeroDelayIsBitIdenticalToTheSimBeforeTheDelay) {
    SimConfig busy = busy_lockstep_config();
    EXPECT_EQ(trajectory_hash(busy, 3000), 0x68f32e510235b633ull);
    busy.coulomb_n = 0.0;
    EXPECT_EQ(trajectory_hash(busy, 3000), 0x222a537a4e400eccull);
    SimConfig hands_off;
    hands_off.clock = SimClock::lockstep;
    EXPECT_EQ(trajectory_hash(hands_off, 3000), 0x7d82cc89cc58bc9dull);
    // And the hash does see the delay: the smallest fraction of a period changes it.
    hands_off.delay_s = 1e-4 * kPeriodS;
    EXPECT_NE(trajectory_hash(hands_off, 3000), 0x7d82cc89cc58bc9dull);
}

// ---------------------------------------------------------------------------------------
// Whole periods: the delayed response is the undelayed one shifted by q ticks, bit for bit.

/// An open-loop command sequence with steps, a ramp and a sine.
double open_loop_force_n(int n) {
    return (n >= 5 && n < 40 ? 2.0 : 0.0) + 0.02 * (n % 17) + std::sin(0.07 * n);
}

void expect_shifted_by(int periods, const HumanModel& human, double coulomb_n) {
    SCOPED_TRACE(testing::Message() << periods << " periods, family "
                                    << static_cast<int>(human.family) << ", F_c " << coulomb_n);
    SimConfig c = lockstep_config();
    c.human[0] = human;
    c.coulomb_n = coulomb_n;
    SimDevice undelayed;
    undelayed.open(c);
    c.delay_s = periods * kPeriodS;
    SimDevice delayed;
    delayed.open(c);
    ASSERT_EQ(delayed.loop_delay().whole_periods, static_cast<std::uint64_t>(periods));
    ASSERT_EQ(delayed.loop_delay().fraction, 0.0);
    std::vector<AxisPlant::State> reference;
    for (int n = 0; n < 400; ++n) {
        ASSERT_EQ(undelayed.write(force(open_loop_force_n(n))), IoResult::ok);
        reference.push_back(undelayed.plant(0).state());
    }
    for (int n = 0; n < 400; ++n) {
        ASSERT_EQ(delayed.write(force(open_loop_force_n(n))), IoResult::ok);
        const AxisPlant::State& s = delayed.plant(0).state();
        if (n < periods) {  // nothing has landed yet: still at rest
            ASSERT_EQ(s.position_m, 0.0) << n;
            ASSERT_EQ(s.velocity_mps, 0.0) << n;
            continue;
        }
        const AxisPlant::State& r = reference[static_cast<std::size_t>(n - periods)];
        ASSERT_EQ(s.position_m, r.position_m) << n;
        ASSERT_EQ(s.velocity_mps, r.velocity_mps) << n;
        ASSERT_EQ(delayed.held_force_n()[0], open_loop_force_n(n - periods)) << n;
    }
    EXPECT_GT(std::abs(reference.back().position_m), 1e-3);  // it did move
}

TEST(SimDelay, WholePeriodsShiftTheResponseByWholeTicks) {
    for (const int periods : {1, 3, 9}) {
        expect_shifted_by(periods, HumanModel{}, 0.0);
        expect_shifted_by(periods, heavy_hand(0.4, 1.5), 0.0);
        expect_shifted_by(periods, heavy_hand(0.4, 1.5), 0.3);  // Coulomb friction too
    }
}

// With a moving set-point the plant is not at rest, so the comparison is of inputs: the
// delayed sim under F[n] is the undelayed sim under F[n-1], bit for bit.
TEST(SimDelay, OnePeriodDelayIsTheUndelayedSimFedTheCommandsOneTickLate) {
    SimConfig c = lockstep_config();
    c.initial_position_m[0] = 0.002;
    c.human[0].family = HumanFamily::two_mass_grasp;
    c.human[0].hand_mass_kg = 0.4;
    c.human[0].skin_stiffness_n_per_m = 3000.0;
    c.human[0].skin_damping_n_s_per_m = 5.0;
    c.human[0].arm_stiffness_n_per_m = 300.0;
    c.human[0].arm_damping_n_s_per_m = 8.0;
    c.human[0].push = PushProfile{0.002, -0.008, 0.02, 0.15, 0.05};
    c.coulomb_n = 0.1;
    SimDevice undelayed;
    undelayed.open(c);
    c.delay_s = kPeriodS;
    SimDevice delayed;
    delayed.open(c);
    for (int n = 0; n < 400; ++n) {
        ASSERT_EQ(undelayed.write(force(n == 0 ? 0.0 : open_loop_force_n(n - 1))), IoResult::ok);
        ASSERT_EQ(delayed.write(force(open_loop_force_n(n))), IoResult::ok);
        const AxisPlant::State& a = undelayed.plant(0).state();
        const AxisPlant::State& b = delayed.plant(0).state();
        ASSERT_EQ(a.position_m, b.position_m) << n;
        ASSERT_EQ(a.velocity_mps, b.velocity_mps) << n;
        ASSERT_EQ(a.mass_position_m, b.mass_position_m) << n;
        ASSERT_EQ(a.mass_velocity_mps, b.mass_velocity_mps) << n;
        ASSERT_EQ(a.set_point_m, b.set_point_m) << n;
    }
}

// ---------------------------------------------------------------------------------------
// Fractional delay: exact against the closed form.

/// m dv/dt + c v = F from rest at t0, at s = t - t0 (zero for s <= 0): with τ = m/c,
///   v = (F/c)(1 - e^{-s/τ}),   x = (F/c)(s - τ(1 - e^{-s/τ})).
struct StepResponse {
    double position_m = 0.0;
    double velocity_mps = 0.0;
};

StepResponse step_response(double mass_kg, double damping_n_s_per_m, double force_n, double s) {
    if (s <= 0.0) return {};
    const double tau = mass_kg / damping_n_s_per_m;
    const double rise = -std::expm1(-s / tau);  // 1 - e^{-s/τ}, accurately
    // s - τ(1 - e^{-s/τ}) = τ (u - 1 + e^{-u}), u = s/τ: summed as a series for small u,
    // where the difference would cancel.
    const double u = s / tau;
    double lag = 0.0;
    if (u < 0.1) {
        double term = u * u / 2.0;  // u^2/2 - u^3/6 + u^4/24 - ...
        for (int k = 3; std::abs(term) > 1e-18 * u * u; ++k) {
            lag += term;
            term *= -u / k;
        }
    } else {
        lag = u - rise;
    }
    return {force_n / damping_n_s_per_m * tau * lag, force_n / damping_n_s_per_m * rise};
}

/// Two force steps written from tick n1 (F1) and from tick n2 (F2 - F1, i.e. F2 from then
/// on): by superposition the response is that of a step of F1 at n1 T + D plus one of
/// F2 - F1 at n2 T + D. Checked at every sample to 1e-12 of the size of the two (their sum
/// crosses zero). The time since a step landed, (n + 1 - n_k - q - φ) T, is formed in
/// periods from the device's own q and φ: t - t0 in seconds would cancel to 1e-12 of a
/// 1e-6 s interval, the rounding of 9.999e-3 s itself.
void expect_exact_steps(double delay_periods, const HumanModel& human) {
    SCOPED_TRACE(testing::Message()
                 << "D = " << delay_periods << " T, family " << static_cast<int>(human.family));
    SimConfig c = lockstep_config(delay_periods * kPeriodS);
    c.human[0] = human;
    SimDevice dev;
    dev.open(c);
    EXPECT_GT(dev.loop_delay().fraction, 0.0);
    const double m = c.mass_kg + human.hand_mass_kg;
    const double b = c.damping_n_s_per_m + human.hand_damping_n_s_per_m;
    const auto q = static_cast<int>(dev.loop_delay().whole_periods);
    const double phi = dev.loop_delay().fraction;
    EXPECT_NEAR(q + phi, delay_periods, 1e-12);
    constexpr int n1 = 3, n2 = 250;
    constexpr double f1 = 1.5, f2 = -0.7;
    for (int n = 0; n < 600; ++n) {
        ASSERT_EQ(dev.write(force(n < n1 ? 0.0 : n < n2 ? f1 : f2)), IoResult::ok);
        const StepResponse a = step_response(m, b, f1, ((n + 1 - n1 - q) - phi) * kPeriodS);
        const StepResponse z = step_response(m, b, f2 - f1, ((n + 1 - n2 - q) - phi) * kPeriodS);
        const double x = a.position_m + z.position_m, v = a.velocity_mps + z.velocity_mps;
        const AxisPlant::State& s = dev.plant(0).state();
        if (x == 0.0) {
            ASSERT_EQ(s.position_m, 0.0) << "tick " << n;  // before the first step lands
            ASSERT_EQ(s.velocity_mps, 0.0) << "tick " << n;
            continue;
        }
        const double x_scale = std::abs(a.position_m) + std::abs(z.position_m);
        const double v_scale = std::abs(a.velocity_mps) + std::abs(z.velocity_mps);
        ASSERT_NEAR(s.position_m, x, 1e-12 * x_scale) << "tick " << n;
        ASSERT_NEAR(s.velocity_mps, v, 1e-12 * v_scale) << "tick " << n;
    }
}

TEST(SimDelay, FractionalDelayStepIsTheClosedFormOfTheMassDamper) {
    expect_exact_steps(0.37, HumanModel{});
    expect_exact_steps(2.37, HumanModel{});
    expect_exact_steps(0.5, heavy_hand(0.2, 0.5));
    expect_exact_steps(9.999, heavy_hand(1.0, 0.0));
}

// The same with Coulomb friction: from rest under F > F_c the handle slides as (10) under
// F - F_c from the moment the force lands (stiction holds it until then).
TEST(SimDelay, FractionalDelayWithCoulombFrictionSlidesExactly) {
    SimConfig c = lockstep_config(0.37 * kPeriodS);
    c.coulomb_n = 1.0;
    SimDevice dev;
    dev.open(c);
    for (int n = 0; n < 500; ++n) {
        dev.write(force(3.0));
        const StepResponse r =
            step_response(0.1, 2.0, 3.0 - 1.0, ((n + 1) - dev.loop_delay().fraction) * kPeriodS);
        ASSERT_NEAR(dev.plant(0).state().position_m, r.position_m,
                    1e-11 * (3.0 - 1.0) / 2.0 * (n + 1) * kPeriodS)
            << n;
        ASSERT_GT(r.position_m, 0.0);
    }
}

TEST(SimDelay, DelayIsSplitIntoWholePeriodsAndAFraction) {
    const LoopDelay none = split_delay(0.0, 1000.0);
    EXPECT_TRUE(none.is_zero());
    EXPECT_EQ(none.units, 0u);
    const LoopDelay one = split_delay(1e-3, 1000.0);
    EXPECT_EQ(one.whole_periods, 1u);
    EXPECT_EQ(one.fraction, 0.0);
    EXPECT_EQ(one.units, kUnitsPerPeriod);
    for (int q = 0; q < 10; ++q) {  // q T, however q * 1e-3 * 1000 rounds
        const LoopDelay whole = split_delay(q * 1e-3, 1000.0);
        EXPECT_EQ(whole.whole_periods, static_cast<std::uint64_t>(q));
        EXPECT_EQ(whole.fraction, 0.0);
    }
    const LoopDelay part = split_delay(2.37e-3, 1000.0);
    EXPECT_EQ(part.whole_periods, 2u);
    EXPECT_NEAR(part.fraction, 0.37, 1e-12);
    EXPECT_EQ(part.units, static_cast<std::uint64_t>(std::llround(2.37 * kUnitsPerPeriod)));
    EXPECT_THROW(split_delay(-1e-9, 1000.0), std::invalid_argument);
    EXPECT_THROW(split_delay(0.01, 1000.0), std::invalid_argument);
    EXPECT_THROW(split_delay(std::nan(""), 1000.0), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------
// The commands in flight.

TEST(SimDelay, ADisabledCommandLandsAfterTheCommandsInFlightAndNothingAfterIt) {
    SimDevice dev;
    dev.open(lockstep_config(2 * kPeriodS));
    Command off = force(5.0);
    off.enable = false;
    // Written: 1, 2, then disabled from tick 2 on. Acting in period n: F[n-2].
    const std::vector<Command> written{force(1.0), force(2.0), off, off, off, off};
    const std::vector<double> acting{0.0, 0.0, 1.0, 2.0, 0.0, 0.0};
    for (std::size_t n = 0; n < written.size(); ++n) {
        ASSERT_EQ(dev.write(written[n]), IoResult::ok);
        EXPECT_EQ(dev.held_force_n()[0], acting[n]) << "period " << n;
        EXPECT_LE(dev.commands_in_flight(), 2u);
    }
    // The zero acted from period 4 on: the handle has coasted since, under (10) alone.
    const double v4 = dev.plant(0).state().velocity_mps;
    EXPECT_GT(v4, 0.0);
    dev.write(off);
    EXPECT_LT(dev.plant(0).state().velocity_mps, v4);
}

TEST(SimDelay, CloseLeavesZeroForceAndDropsTheCommandsInFlight) {
    SimDevice dev;
    dev.open(lockstep_config(3.5 * kPeriodS));
    for (int n = 0; n < 6; ++n) dev.write(force(2.0 + n));
    EXPECT_EQ(dev.held_force_n()[0], 4.0);    // F[2] acts at the end of period 5
    EXPECT_EQ(dev.commands_in_flight(), 3u);  // F[3], F[4], F[5]
    dev.close();
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    EXPECT_EQ(dev.commands_in_flight(), 0u);
    Sample s;
    EXPECT_EQ(dev.read(s), IoResult::disconnected);
    EXPECT_EQ(dev.write(force(1.0)), IoResult::disconnected);
    EXPECT_EQ(dev.commands_in_flight(), 0u);
    // Opened again, nothing of the old run is in flight.
    dev.open(lockstep_config(3.5 * kPeriodS));
    for (int n = 0; n < 3; ++n) {
        dev.write(Command{});
        EXPECT_EQ(dev.held_force_n()[0], 0.0);
        EXPECT_EQ(dev.plant(0).state().position_m, 0.0);
    }
}

TEST(SimDelay, ADisconnectDropsTheCommandsInFlight) {
    SimConfig c = lockstep_config(4 * kPeriodS);
    c.faults.disconnect_at_s = 0.0105;  // hits sample 11
    SimDevice dev;
    dev.open(c);
    Sample s;
    for (int n = 0; n < 30; ++n) {
        const IoResult r = dev.read(s);
        dev.write(force(1.0));
        if (n <= 10) {
            EXPECT_EQ(r, IoResult::ok) << n;
            EXPECT_EQ(dev.held_force_n()[0], n >= 4 ? 1.0 : 0.0) << n;
        } else {
            EXPECT_EQ(r, IoResult::disconnected) << n;
            EXPECT_EQ(dev.held_force_n()[0], 0.0) << n;
            EXPECT_EQ(dev.commands_in_flight(), 0u) << n;
        }
    }
}

TEST(SimDelay, ARefusedCommandCutsTheForceAtOnce) {
    SimDevice dev;
    dev.open(lockstep_config(2 * kPeriodS));
    for (int n = 0; n < 5; ++n) dev.write(force(1.0));
    EXPECT_EQ(dev.held_force_n()[0], 1.0);
    EXPECT_EQ(dev.write(force(std::nan(""))), IoResult::error);
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    EXPECT_EQ(dev.commands_in_flight(), 0u);
    dev.write(force(2.0));  // lands two periods later; zero until then
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    dev.write(force(2.0));
    EXPECT_EQ(dev.held_force_n()[0], 0.0);
    dev.write(force(2.0));
    EXPECT_EQ(dev.held_force_n()[0], 2.0);
}

// ---------------------------------------------------------------------------------------
// Each sample says which write() is in effect and since when: what the link diagnosis
// measures the delay from.

TEST(SimDelay, SamplesSayWhichCommandActsAndSinceWhenExactly) {
    for (const double periods : {0.0, 0.5, 1.0, 1.5, 9.75}) {
        SimDevice dev;
        dev.open(lockstep_config(periods * kPeriodS));
        EXPECT_TRUE(dev.info().samples_at_read);
        Sample s;
        ASSERT_EQ(dev.read(s), IoResult::ok);
        EXPECT_EQ(s.applied, servo::AppliedReport::none);  // nothing written yet
        int reported = 0;
        for (std::uint64_t n = 1; n <= 30; ++n) {
            const double sample_s = s.device_time_s;  // the sample write n is computed from
            ASSERT_EQ(dev.write(force(0.1)), IoResult::ok);
            ASSERT_EQ(dev.read(s), IoResult::ok);
            if (s.applied == servo::AppliedReport::none) continue;
            ASSERT_EQ(s.applied, servo::AppliedReport::reported);
            // The newest landed: write n - q for the q whole periods still in flight.
            const auto in_flight = static_cast<std::uint64_t>(std::floor(periods));
            ASSERT_EQ(s.applied_write, n - in_flight) << periods;
            // It landed D after the sample it was computed from, n - q - 1 periods ago.
            const double computed_from_s = sample_s - static_cast<double>(in_flight) * kPeriodS;
            EXPECT_NEAR(s.applied_time_s - computed_from_s, periods * kPeriodS, 1e-12)
                << periods << " write " << n;
            ++reported;
        }
        EXPECT_EQ(reported, 30 - static_cast<int>(std::floor(periods))) << periods;
    }
}

TEST(SimDelay, ARefusedCommandTakesEffectAtOnceAsZero) {
    SimDevice dev;
    dev.open(lockstep_config(2 * kPeriodS));
    for (int n = 0; n < 5; ++n) dev.write(force(1.0));
    Sample s;
    dev.read(s);
    EXPECT_EQ(s.applied_write, 3u);
    EXPECT_EQ(dev.write(force(std::nan(""))), IoResult::error);  // write 6, at t = 5 ms
    dev.read(s);
    EXPECT_EQ(s.applied_write, 6u);
    EXPECT_DOUBLE_EQ(s.applied_time_s, 5 * kPeriodS);
}

TEST(SimDelay, TheRealtimeClockReportsWhenEachCommandLanded) {
    SimConfig c = lockstep_config(1.5 * kPeriodS);
    c.clock = SimClock::realtime;
    SimDevice dev;
    dev.open(c);
    EXPECT_TRUE(dev.info().samples_at_read);
    Sample s;
    dev.read(s);
    const double first_sample_s = s.device_time_s;
    dev.write(force(0.5));  // lands 1.5 ms after that sample
    timespec pause{0, 3'000'000};
    nanosleep(&pause, nullptr);
    dev.read(s);
    ASSERT_EQ(s.applied, servo::AppliedReport::reported);
    EXPECT_EQ(s.applied_write, 1u);
    // Quantised to 2^-20 period.
    EXPECT_NEAR(s.applied_time_s - first_sample_s, 1.5 * kPeriodS, 2e-9);
    // Written after its landing time had passed, it lands at once.
    nanosleep(&pause, nullptr);
    dev.write(force(0.5));
    dev.read(s);
    EXPECT_EQ(s.applied_write, 2u);
    EXPECT_GE(s.applied_time_s - first_sample_s, 3e-3);
}

TEST(SimDelay, APipelineThatOverflowsKeepsTheNewestCommand) {
    CommandPipeline pipeline;
    pipeline.configure(3);
    EXPECT_EQ(pipeline.due(100), nullptr);
    pipeline.push(10, {1.0});
    pipeline.push(20, {2.0});
    pipeline.push(30, {3.0});
    pipeline.push(40, {4.0});  // full: replaces the one due at 30
    EXPECT_EQ(pipeline.size(), 3u);
    EXPECT_EQ(pipeline.due(9), nullptr);
    std::vector<std::uint64_t> due;
    std::vector<double> forces;
    while (const PendingCommand* c = pipeline.due(1000)) {
        due.push_back(c->due);
        forces.push_back(c->force_n[0]);
        pipeline.pop();
    }
    EXPECT_EQ(due, (std::vector<std::uint64_t>{10, 20, 40}));
    EXPECT_EQ(forces, (std::vector<double>{1.0, 2.0, 4.0}));
    pipeline.push(50, {5.0});  // wraps around the ring
    pipeline.clear();
    EXPECT_EQ(pipeline.due(1000), nullptr);
}

}  // namespace
}  // namespace hapticd::device::sim
