// The passive model (passive_model.hpp): Colgate and Schenkel's condition with a loop delay,
// worst-cased over every passive environment, against brute force and its closed forms.
#include "hapticd/theory/passive_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "hapticd/theory/benchmark.hpp"
#include "hapticd/theory/coupling_check.hpp"

namespace hapticd::theory {
namespace {

constexpr double kT = 1e-3;
constexpr double kPi = std::numbers::pi;
const DeviceModel kPen{0.1, 2.0};

/// The virtual wall K, B as an impedance on the backward-difference velocity.
Complex wall_impedance(double k, double b, double theta) {
    return coupling_impedance(SpringDamperCoupling{k, b}, theta, kT);
}

TEST(PortDampingNeeded, IsColgateAndSchenkelsConditionWithNoDelay) {
    // b >= (T/2) Re{(1 - e^{-jθ}) H} / (1 - cos θ), H = K + B (1 - z⁻¹)/T, computed directly.
    const Complex j(0.0, 1.0);
    for (double theta : {1e-3, 0.2, 1.0, 2.5, kPi}) {
        for (auto [k, b] : {std::pair{1000.0, 0.0}, {3000.0, 0.7}, {0.0, 1.5}}) {
            const Complex e = std::exp(-j * theta);
            const Complex h = k + b * (1.0 - e) / kT;
            const double expected =
                std::max(0.0, (kT / 2.0) * ((1.0 - e) * h).real() / (1.0 - std::cos(theta)));
            EXPECT_NEAR(port_damping_needed(wall_impedance(k, b, theta), theta, 0.0), expected,
                        1e-9 * (1.0 + expected))
                << "theta " << theta << " K " << k << " B " << b;
        }
    }
    // The classic virtual-wall bound, b > K T/2 + B, is reached at Nyquist.
    EXPECT_NEAR(port_damping_needed(wall_impedance(3000.0, 0.7, kPi), kPi, 0.0), 1.5 + 0.7, 1e-12);
}

TEST(PortDampingNeeded, WholePeriodsOfDelayRotateTheImpedance) {
    for (double theta : {0.01, 0.7, 2.0, kPi - 1e-3}) {
        const Complex z = wall_impedance(2000.0, 0.3, theta);
        for (int q : {1, 2, 5}) {
            const double expected =
                std::max(0.0, -(z * std::polar(1.0, -(1.0 + q) * theta)).real());
            EXPECT_NEAR(port_damping_needed(z, theta, q), expected, 1e-9 * (1.0 + expected));
        }
    }
}

TEST(PortDampingNeeded, LowFrequencySpringNeedsTheDelayedHalfSample) {
    // A spring with D periods of delay: b >= K T (1/2 + φ + sqrt(1/4 + 2φ))/2 as θ -> 0 for
    // D = φ < 1 (docs/stability-models.md), which is K T (1 + 2D)/2 at φ = 0 and φ = 1.
    const double k = 1000.0;
    const double theta = 1e-5;
    for (double phi : {0.0, 0.25, 0.5, 0.9}) {
        const double expected = k * kT / 2.0 * (0.5 + phi + std::sqrt(0.25 + 2.0 * phi));
        EXPECT_NEAR(port_damping_needed(wall_impedance(k, 0.0, theta), theta, phi), expected,
                    1e-4 * expected)
            << phi;
    }
    EXPECT_NEAR(port_damping_needed(wall_impedance(k, 0.0, theta), theta, 1.0), 1.5 * k * kT, 1e-4);
}

/// max over lossless environments Y_e = j h of the damping the port needs with the coupling
/// in series, times 2 Re(1/Z_c): brute force over h on a tan-spaced grid of 200001 points.
double brute_force_numerator(const SpringDamperCoupling& coupling, double theta, double delay) {
    const Complex zc = coupling_impedance(coupling, theta, kT);
    const double scale = std::abs(1.0 / zc);
    double worst = 0.0;
    constexpr int kPoints = 200001;
    for (int i = 1; i < kPoints; ++i) {
        const double t = -1.0 + 2.0 * i / kPoints;
        const double h = scale * std::tan(kPi / 2.0 * t);
        const Complex z = 1.0 / (1.0 / zc + Complex(0.0, h));
        worst = std::max(worst, port_damping_needed(z, theta, delay));
    }
    worst = std::max(worst, port_damping_needed(zc, theta, delay));  // h = 0
    return worst * 2.0 * (1.0 / zc).real();
}

class EveryDelay : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Periods, EveryDelay,
                         ::testing::Values(0.0, 0.1, 0.37, 0.5, 0.9, 1.0, 1.5, 2.25, 9.9));

TEST_P(EveryDelay, WorstEnvironmentFactorsOutOfTheCoupling) {
    // The worst passive environment costs M(θ)/(2 Re(1/Z_c)) of device damping, the same M
    // for every coupling: the condition has the shape of (21).
    const double delay = GetParam();
    for (double theta : {0.003, 0.1, 0.5, 1.3, 2.2, 3.0, kPi}) {
        const double m = passive_hold_numerator(theta, delay);
        for (const SpringDamperCoupling c :
             {SpringDamperCoupling{1000.0, 0.2}, {3000.0, 0.05}, {40.0, 2.0}}) {
            const double brute = brute_force_numerator(c, theta, delay);
            EXPECT_GE(m, brute * (1.0 - 1e-9)) << "theta " << theta;
            EXPECT_NEAR(m, brute, 2e-5 * m + 1e-12)
                << "theta " << theta << " k_c " << c.stiffness_n_per_m;
        }
    }
}

TEST_P(EveryDelay, LowFrequencyLimitIsTauSquaredOverTwo) {
    const double delay = GetParam();
    const double tau = passive_delay_samples(delay);
    const double theta = 1e-4;
    EXPECT_NEAR(passive_hold_numerator(theta, delay) / (theta * theta / 2.0), tau * tau,
                1e-6 * tau * tau);
}

TEST(PassiveHoldNumerator, WholePeriodsAreTheAliasSumWithTheDelay) {
    for (int q : {0, 1, 3}) {
        for (double theta : {1e-3, 0.4, 1.7, kPi}) {
            EXPECT_NEAR(passive_hold_numerator(theta, q), 1.0 - std::cos((1.0 + q) * theta), 1e-12);
        }
    }
    EXPECT_DOUBLE_EQ(passive_delay_samples(0.0), 1.0);
    EXPECT_DOUBLE_EQ(passive_delay_samples(2.0), 3.0);
    // Halfway between whole periods the fraction costs more than the naive e^{-j(1+d)θ}:
    // τ² = (1.5)² + 1/4 = 2.5 against 2.25.
    EXPECT_NEAR(passive_delay_samples(0.5), std::sqrt(2.5), 1e-15);
}

// The independent lifted computation (tools/scripts/lifted_passivity.py, no alias sums):
// its worst case over every passive environment, per frequency, at half a period of delay.
TEST(PassiveHoldNumerator, MatchesTheLiftedReferenceAtHalfAPeriod) {
    const std::pair<double, double> lifted[] = {
        {0.01, 1.24996e-4}, {0.1, 0.01246463}, {0.5, 0.29105757}, {1.0, 0.93792227},
        {2.0, 1.5348952},   {3.0, 1.0149111},  {kPi, 1.0}};
    for (auto [theta, reference] : lifted) {
        EXPECT_NEAR(passive_hold_numerator(theta, 0.5), reference, 5e-8 * reference + 1e-9)
            << theta;
    }
}

TEST(PassiveHoldNumerator, IsContinuousAcrossWholePeriods) {
    for (double theta : {0.05, 1.0, 2.8}) {
        EXPECT_NEAR(passive_hold_numerator(theta, 1.0 - 1e-9), passive_hold_numerator(theta, 1.0),
                    1e-6);
        EXPECT_NEAR(passive_hold_numerator(theta, 1e-9), passive_hold_numerator(theta, 0.0), 1e-6);
    }
}

TEST(PassiveModel, RigidWallOptimumIsColgatesBoundWithNoDelay) {
    // Against every passive operator and environment, b_c + k_c T/2 <= b: the bound binds at
    // Nyquist for every b_c, so damping buys no stiffness.
    for (double bc : {0.0, 0.234, 1.0}) {
        const double limit = 2.0 * (2.0 - bc) / kT;
        EXPECT_TRUE(check_coupling(kPen, {limit * (1.0 - 1e-9), bc}, HoldModel::passive, 1000.0)
                        .unconditionally_stable)
            << bc;
        const CouplingCheck over =
            check_coupling(kPen, {limit * (1.0 + 1e-6), bc}, HoldModel::passive, 1000.0);
        EXPECT_FALSE(over.unconditionally_stable) << bc;
        if (bc > 0.0) {
            EXPECT_NEAR(over.worst_frequency_hz, 500.0, 1e-6);
        }
    }
}

TEST(PassiveModel, OnePeriodOfDelayQuartersTheStiffness) {
    // d = 1, b_c = 0: Re(1/Z_c) = sin²(θ/2)/R >= sin²θ/b needs b >= 4 R cos²(θ/2), worst as
    // θ -> 0: k_c <= b/(2T), a quarter of 2b/T (the heavy hand alone allows a third).
    const LoopModel delayed{HoldModel::passive, 1.0};
    const double limit = 2.0 / (2.0 * kT);
    EXPECT_TRUE(
        check_coupling(kPen, {limit * (1.0 - 1e-6), 0.0}, delayed, 1000.0).unconditionally_stable);
    const CouplingCheck over = check_coupling(kPen, {limit * (1.0 + 1e-6), 0.0}, delayed, 1000.0);
    EXPECT_FALSE(over.unconditionally_stable);
    EXPECT_EQ(over.worst_frequency_hz, 0.0);  // binds in the limit f -> 0
}

TEST(PassiveModel, HoldTermIsTheDelayedExactHold) {
    const LoopModel delayed{HoldModel::passive, 1.5};
    for (double theta : {0.3, 2.0}) {
        const Complex h = hold_term(delayed, theta);
        EXPECT_NEAR(std::abs(h), 1.0, 1e-15);
        EXPECT_NEAR(std::arg(h), std::remainder(-2.5 * theta, 2.0 * kPi), 1e-12);
    }
    EXPECT_EQ(parse_hold_model("passive"), HoldModel::passive);
    EXPECT_EQ(to_string(HoldModel::passive), "passive");
}

}  // namespace
}  // namespace hapticd::theory
