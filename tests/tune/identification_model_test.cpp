// The model haptic-tune identify fits (identification_model.hpp): its exact hold against the
// sim device's plant and against closed forms worked by hand, stops and reversals inside a
// hold, stiction, and its automatic derivatives against finite differences.
#include "hapticd/tune/identification_model.hpp"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "hapticd/device/sim/sim_device.hpp"

namespace hapticd::tune {
namespace {

constexpr double kMass = 0.1;
constexpr double kDamping = 2.0;
constexpr double kPeriod = 1e-3;

/// One hold with doubles.
MotionState<double> step(MotionState<double> s, double push, double coulomb, double h = kPeriod,
                         double mass = kMass, double damping = kDamping) {
    const double a = damping / mass;
    hold_step(s, mass, a, coulomb, push, hold_constants(a, h), h);
    return s;
}

device::sim::SimDevice open_sim(double coulomb_n) {
    device::sim::SimConfig config;
    config.mass_kg = kMass;
    config.damping_n_s_per_m = kDamping;
    config.coulomb_n = coulomb_n;
    config.clock = device::sim::SimClock::lockstep;
    device::sim::SimDevice sim;
    sim.open(config);
    return sim;
}

std::vector<double> random_forces(std::size_t count, double scale, unsigned seed) {
    std::mt19937 random(seed);
    std::normal_distribution<double> normal(0.0, scale);
    std::vector<double> forces(count);
    for (double& f : forces) f = normal(random);
    return forces;
}

TEST(IdentificationModel, HoldConstantsMatchTheirDefinitionAndTheSmallRateSeries) {
    for (double a : {1e-6, 1e-3, 0.5, 9.99, 10.01, 20.0, 1e4}) {
        const HoldConstants<double> c = hold_constants(a, kPeriod);
        // The reference in long double, without cancellation: expm1, and for phi2 its series
        // h² Σ (-z)^k/(k+2)! where z < 1.
        const long double z = static_cast<long double>(a) * kPeriod;
        const long double phi1 = -std::expm1(-z) / a;
        long double phi2 = 0.0L;
        if (z < 1.0L) {
            long double term = 0.5L;  // (-z)^0 / 2!
            for (int k = 0; k < 30; ++k) {
                phi2 += term;
                term *= -z / (k + 3);
            }
            phi2 *= static_cast<long double>(kPeriod) * kPeriod;
        } else {
            phi2 = (kPeriod - phi1) / a;
        }
        EXPECT_NEAR(c.decay, static_cast<double>(std::exp(-z)), 1e-15) << a;
        EXPECT_NEAR(c.phi1 / static_cast<double>(phi1), 1.0, 1e-14) << a;
        EXPECT_NEAR(c.phi2 / static_cast<double>(phi2), 1.0, 1e-12) << a;
    }
    // Continuous across the switch to the series at z = 1e-2.
    const double below = hold_constants(9.999999, kPeriod).phi2;
    const double above = hold_constants(10.000001, kPeriod).phi2;
    EXPECT_NEAR(below / above, 1.0, 1e-6);
}

TEST(IdentificationModel, LinearHoldMatchesTheSimDeviceExactly) {
    device::sim::SimDevice sim = open_sim(0.0);
    MotionState<double> model{0.0, 0.0};
    for (double f : random_forces(3000, 1.0, 7)) {
        servo::Command command;
        command.enable = true;
        command.force_n[0] = f;
        sim.write(command);
        model = step(model, f, 0.0);
        ASSERT_NEAR(model.x, sim.plant(0).state().position_m, 1e-12);
        ASSERT_NEAR(model.v, sim.plant(0).state().velocity_mps, 1e-11);
    }
}

TEST(IdentificationModel, CoulombHoldAgreesWithTheSimsSubsteppedFriction) {
    // The sim integrates friction in 32 substeps per period and stops the handle at the
    // substep where v would change sign (first order in T/32); the model finds the stop in
    // closed form. From the sim's state, one hold of the model lands within a small fraction
    // of a 10 µm count of the sim's, through moving, stopping, sticking and breaking away.
    device::sim::SimDevice sim = open_sim(0.3);
    double worst = 0.0;
    int stuck_periods = 0;
    for (double f : random_forces(3000, 0.5, 11)) {
        const MotionState<double> before{sim.plant(0).state().position_m,
                                         sim.plant(0).state().velocity_mps};
        servo::Command command;
        command.enable = true;
        command.force_n[0] = f;
        sim.write(command);
        const MotionState<double> model = step(before, f, 0.3);
        stuck_periods += model.v == 0.0;
        worst = std::max(worst, std::abs(model.x - sim.plant(0).state().position_m));
    }
    EXPECT_GT(stuck_periods, 300);  // the run does stick and slip
    EXPECT_LT(worst, 1e-6);
}

TEST(IdentificationModel, AHoldThatStopsAndReversesFollowsTheClosedFormPiecewise) {
    // Moving at +5 mm/s under a push of -1 N with F_c = 0.1 N: the net force -1.1 N stops
    // the handle at t1 = (m/b) ln(1 + v0 b/1.1), then -0.9 N drives it back for the rest.
    const double v0 = 0.005;
    const double a = kDamping / kMass;
    const double t1 = std::log(1.0 + v0 * kDamping / 1.1) / a;
    ASSERT_LT(t1, kPeriod);
    const auto free_motion = [&](double x, double v, double force, double t) {
        const double terminal = force / kDamping;
        return MotionState<double>{x + terminal * t + (v - terminal) * (1.0 - std::exp(-a * t)) / a,
                                   terminal + (v - terminal) * std::exp(-a * t)};
    };
    const MotionState<double> stop = free_motion(0.0, v0, -1.1, t1);
    EXPECT_NEAR(stop.v, 0.0, 1e-15);
    const MotionState<double> expected = free_motion(stop.x, 0.0, -0.9, kPeriod - t1);
    const MotionState<double> got = step({0.0, v0}, -1.0, 0.1);
    EXPECT_NEAR(got.x, expected.x, 1e-16);
    EXPECT_NEAR(got.v, expected.v, 1e-14);
    EXPECT_LT(got.v, 0.0);
}

TEST(IdentificationModel, StictionHoldsTheHandleWhileThePushIsBelowFriction) {
    // Stops inside the hold and stays: the push 0.05 N cannot overcome F_c = 0.1 N.
    const MotionState<double> stopped = step({0.0, 1e-4}, 0.05, 0.1);
    EXPECT_EQ(stopped.v, 0.0);
    EXPECT_GT(stopped.x, 0.0);
    // At rest it stays put, exactly, for as long as |push| <= F_c ...
    MotionState<double> s = stopped;
    for (double push : {0.1, -0.1, 0.0, 0.099}) {
        s = step(s, push, 0.1);
        EXPECT_EQ(s.x, stopped.x);
        EXPECT_EQ(s.v, 0.0);
    }
    // ... and breaks away in the push's direction once it exceeds F_c.
    s = step(s, -0.3, 0.1);
    EXPECT_LT(s.v, 0.0);
    EXPECT_NEAR(s.v, -0.2 / kMass * hold_constants(kDamping / kMass, kPeriod).phi1, 1e-15);
}

TEST(IdentificationModel, JetDerivativesMatchFiniteDifferences) {
    // A sequence that moves, stops, sticks and reverses; derivatives with respect to
    // (log m, log b, F_c, F_0, x0, v0) of the final position.
    using Jet = ceres::Jet<double, 6>;
    const std::vector<double> forces = {0.8, -0.5, -0.5, 0.05, 0.05, 0.6, -1.0, 0.3, 0.0, -0.2};
    const auto simulate = [&](const auto* p) {
        using T = std::remove_const_t<std::remove_pointer_t<decltype(p)>>;
        const T mass = exp(p[0]);
        const T a = exp(p[1]) / mass;
        const HoldConstants<T> full = hold_constants(a, kPeriod);
        MotionState<T> s{p[4], p[5]};
        for (double f : forces) hold_step(s, mass, a, p[2], T(f) + p[3], full, kPeriod);
        return s.x;
    };
    const double p0[6] = {std::log(kMass), std::log(kDamping), 0.15, 0.02, 0.001, 0.01};
    Jet jets[6];
    for (int i = 0; i < 6; ++i) jets[i] = Jet(p0[i], i);
    const Jet x = simulate(jets);
    for (int i = 0; i < 6; ++i) {
        const double h = 1e-7 * std::max(1.0, std::abs(p0[i]));
        double up[6], down[6];
        std::copy(p0, p0 + 6, up);
        std::copy(p0, p0 + 6, down);
        up[i] += h;
        down[i] -= h;
        const double numeric = (simulate(up) - simulate(down)) / (2.0 * h);
        EXPECT_NEAR(x.v[i], numeric, 1e-6 * std::max(1e-3, std::abs(numeric))) << "parameter " << i;
    }
}

TEST(HoldDelay, SplitsTheDelayIntoWholePeriodsAndAFraction) {
    const HoldDelay none = split_hold_delay(0.0, 1e-3);
    EXPECT_EQ(none.whole_periods, 0u);
    EXPECT_EQ(none.fraction, 0.0);
    EXPECT_EQ(none.history(), 0u);
    const HoldDelay one = split_hold_delay(1e-3, 1.0 / 1000.0);  // whatever the rounding
    EXPECT_EQ(one.whole_periods, 1u);
    EXPECT_EQ(one.fraction, 0.0);
    EXPECT_EQ(one.history(), 1u);
    const HoldDelay part = split_hold_delay(0.55e-3, 1e-3);
    EXPECT_EQ(part.whole_periods, 0u);
    EXPECT_NEAR(part.fraction, 0.55, 1e-12);
    EXPECT_EQ(part.history(), 1u);
    const HoldDelay more = split_hold_delay(2.3e-3, 1e-3);
    EXPECT_EQ(more.whole_periods, 2u);
    EXPECT_NEAR(more.fraction, 0.3, 1e-12);
    EXPECT_EQ(more.history(), 3u);
}

}  // namespace
}  // namespace hapticd::tune
