// The exact model held against the passive bound (docs/stability-models.md): where the theory
// says the bound is tight, the exact model's synthesised adversaries reach it; below it,
// nothing in the sweep or among the adversaries is unstable.
//
// The passive bound is a bisection on check_coupling(passive) here, not a closed form, so
// the test holds the two implementations against each other; the closed forms are tested in
// tests/theory/passive_model_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <string>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/operator_synthesis.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::HoldModel;
using theory::SpringDamperCoupling;

const DeviceModel kPen{0.1, 2.0};  // m = 0.1 kg, b = 2 N s/m
constexpr double kRateHz = 1000.0;
constexpr double kPeriodS = 1.0 / kRateHz;

/// The largest k_c the passive model allows at b_c (on a velocity filter at `filter_hz`), to
/// 1e-9 relative.
double passive_limit(const DeviceModel& device, double bc, double delay_periods, double rate_hz,
                     double filter_hz = 0.0) {
    double lo = 0.0, hi = 1e7;
    while (hi - lo > 1e-9 * hi) {
        const double mid = 0.5 * (lo + hi);
        const bool stable = theory::check_coupling(device, {mid, bc, filter_hz},
                                                   {HoldModel::passive, delay_periods}, rate_hz)
                                .unconditionally_stable;
        (stable ? lo : hi) = mid;
    }
    return lo;
}

TEST(PassiveLimit, RigidWallOptimumIsColgatesBoundForEveryDamping) {
    for (double bc : {0.0, 0.234, 0.6, 1.0}) {
        EXPECT_NEAR(passive_limit(kPen, bc, 0.0, kRateHz),
                    2.0 * (kPen.damping_n_s_per_m - bc) / kPeriodS, 1e-5)
            << bc;
    }
}

struct Design {
    double coupling_damping;
    double delay_periods;
};

class TightWithWholePeriods : public ::testing::TestWithParam<Design> {};
INSTANTIATE_TEST_SUITE_P(Designs, TightWithWholePeriods,
                         ::testing::Values(Design{0.0, 0.0}, Design{0.234, 0.0}, Design{0.6, 0.0},
                                           Design{1.0, 0.0}, Design{0.0, 1.0}, Design{0.3, 1.0},
                                           Design{0.0, 2.0}));

// 3 % past the bound the exact model finds the loop unstable and names the operator; 1 %
// inside it, stable. For b_c > 0 without delay the bound binds at Nyquist and only an
// operator with several modes on the odd harmonics of Nyquist reaches it (the issue's
// S_N: with 16 modes, (π²/8)/S_16 = 1.013 < 1.03).
TEST_P(TightWithWholePeriods, UnstableJustAboveStableJustBelow) {
    const Design d = GetParam();
    const double limit = passive_limit(kPen, d.coupling_damping, d.delay_periods, kRateHz);
    const ExactCheck above =
        check_exact(kPen, {1.03 * limit, d.coupling_damping}, kRateHz, d.delay_periods);
    EXPECT_FALSE(above.stable) << "k_c = " << 1.03 * limit;
    EXPECT_GT(above.worst_spectral_radius, 1.0 + 1e-7);
    EXPECT_FALSE(above.worst_operator.describe().empty());
    EXPECT_EQ(above.delay_periods, d.delay_periods);
    if (d.coupling_damping > 0.0 && d.delay_periods == 0.0) {
        EXPECT_EQ(above.worst_operator.family, OperatorFamily::multi_mode)
            << above.worst_operator.describe();
        EXPECT_NEAR(above.worst_frequency_hz, kRateHz / 2.0, 1e-3);
    }
    const ExactCheck below =
        check_exact(kPen, {0.99 * limit, d.coupling_damping}, kRateHz, d.delay_periods);
    EXPECT_TRUE(below.stable) << below.worst_operator.describe() << " | "
                              << below.worst_environment.describe() << " |z| "
                              << below.worst_spectral_radius;
}

// The damper on a filtered velocity (theory/velocity_filter.hpp): the same tightness. With no
// delay the passive bound is k_c T/2 + b_c (1 - a)/(1 + a) <= b (docs/stability-models.md),
// binding at Nyquist, where the filtered damper weighs (1 - a)/(1 + a) of b_c; with a period of
// delay it binds in the band, where the filter's lag takes damping away.
struct FilteredDesign {
    double filter_hz;
    double coupling_damping;
    double delay_periods;
};

class TightWithAVelocityFilter : public ::testing::TestWithParam<FilteredDesign> {};
INSTANTIATE_TEST_SUITE_P(Designs, TightWithAVelocityFilter,
                         ::testing::Values(FilteredDesign{100.0, 0.5, 0.0},
                                           FilteredDesign{300.0, 0.5, 0.0},
                                           FilteredDesign{100.0, 0.5, 1.0},
                                           FilteredDesign{300.0, 0.5, 1.0}));

TEST_P(TightWithAVelocityFilter, UnstableJustAboveStableJustBelow) {
    const FilteredDesign d = GetParam();
    const double limit =
        passive_limit(kPen, d.coupling_damping, d.delay_periods, kRateHz, d.filter_hz);
    if (d.delay_periods == 0.0) {
        const double a = std::exp(-2.0 * std::numbers::pi * d.filter_hz * kPeriodS);
        EXPECT_NEAR(
            limit,
            2.0 * (kPen.damping_n_s_per_m - d.coupling_damping * (1.0 - a) / (1.0 + a)) / kPeriodS,
            1e-5 * limit);
    }
    const ExactCheck above = check_exact(kPen, {1.03 * limit, d.coupling_damping, d.filter_hz},
                                         kRateHz, d.delay_periods);
    EXPECT_FALSE(above.stable) << "k_c = " << 1.03 * limit;
    EXPECT_GT(above.worst_spectral_radius, 1.0 + 1e-7);
    std::cout.precision(9);
    std::cout << "[filtered] f_c " << d.filter_hz << " Hz, b_c " << d.coupling_damping << ", delay "
              << d.delay_periods << ": passive limit " << limit
              << " N/m; 1.03x: |z| = " << above.worst_spectral_radius << " at "
              << above.worst_frequency_hz << " Hz, " << above.worst_operator.describe() << " | "
              << above.worst_environment.describe() << "\n";
    std::cout.precision(6);
    if (d.delay_periods == 0.0) {
        EXPECT_EQ(above.worst_operator.family, OperatorFamily::multi_mode)
            << above.worst_operator.describe();
        EXPECT_NEAR(above.worst_frequency_hz, kRateHz / 2.0, 1e-3);
    }
    const ExactCheck below = check_exact(kPen, {0.99 * limit, d.coupling_damping, d.filter_hz},
                                         kRateHz, d.delay_periods);
    EXPECT_TRUE(below.stable) << below.worst_operator.describe() << " | "
                              << below.worst_environment.describe() << " |z| "
                              << below.worst_spectral_radius;
}

// No design inside the passive bound may be unstable for any operator or environment the
// exact model knows, fractional delays included: random designs from a fixed seed.
TEST(PassiveBound, NoDesignBelowItIsUnstable) {
    std::mt19937 random(20261201);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 5; ++i) {
        const DeviceModel device{0.05 + 0.5 * unit(random), 0.5 + 4.0 * unit(random)};
        const double rate = i % 2 == 0 ? 1000.0 : 2000.0;
        const double delay = 3.0 * unit(random);
        const double limit = passive_limit(device, 0.0, delay, rate);
        // b_c up to 80 % of what the bound's peak leaves.
        const double bc = 0.8 * unit(random) * device.damping_n_s_per_m /
                          std::max(1.0, (1.0 + delay) * (1.0 + delay));
        const double k = (0.3 + 0.69 * unit(random)) * passive_limit(device, bc, delay, rate);
        ASSERT_GT(limit, 0.0);
        const ExactCheck check = check_exact(device, {k, bc}, rate, delay);
        EXPECT_TRUE(check.stable) << "m " << device.mass_kg << " b " << device.damping_n_s_per_m
                                  << " rate " << rate << " delay " << delay << " k_c " << k
                                  << " b_c " << bc << ": " << check.worst_operator.describe()
                                  << " | " << check.worst_environment.describe();
    }
}

// The issue's reproduction: k_c = 4300 N/m, b_c = 0.234 N s/m was the documented "exact
// optimum" (4467 N/m at 0.234). A lossless two-mass grasp with free-handle modes at 500 Hz
// and 1500 Hz makes it grow by |z| = 1.0001 per tick, and the exact check now says so.
TEST(PassiveBound, TheIssuesTwoMassGraspBreaksTheOldExactOptimum) {
    const OperatorModel grasp = OperatorModel::two_mass_grasp(7.926e6, 0.0, 0.946, 1.0464e7, 0.0);
    const ClosedLoopPoles poles =
        closed_loop_poles(kPen, {4300.0, 0.234}, kRateHz, grasp, EnvironmentModel::rigid_wall());
    EXPECT_NEAR(poles.spectral_radius, 1.0001, 2e-5);
    EXPECT_NEAR(poles.dominant_frequency_hz, 500.0, 1e-3);
    const ExactCheck check = check_exact(kPen, {4300.0, 0.234}, kRateHz);
    EXPECT_FALSE(check.stable);
    EXPECT_FALSE(theory::check_coupling(kPen, {4300.0, 0.234}, HoldModel::passive, kRateHz)
                     .unconditionally_stable);
}

// The synthesis: the alias-tuned operator puts the handle's free modes on the aliases, so
// the handle (device mass included) has zero reactance there.
TEST(OperatorSynthesis, FreeHandleModesSitOnTheAliases) {
    const double theta = 2.0;
    const OperatorModel h = alias_tuned_operator(kPen, theta, kRateHz, 4, 0.0);
    ASSERT_EQ(h.modes.size(), 4u);
    for (double omega : alias_frequencies_rad_per_s(theta, kRateHz, 4)) {
        // Handle reactance: m ω + Σ m_i ω ω_i²/(ω_i² - ω²).
        double x = (kPen.mass_kg + h.hand_mass_kg) * omega - h.hand_stiffness_n_per_m / omega;
        double scale = kPen.mass_kg * omega;
        for (const OperatorMode& mode : h.modes) {
            const double w2 = mode.stiffness_n_per_m / mode.mass_kg;
            x += mode.mass_kg * omega * w2 / (w2 - omega * omega);
            scale += std::abs(mode.mass_kg * omega * w2 / (w2 - omega * omega));
        }
        EXPECT_NEAR(x, 0.0, 1e-9 * scale) << omega;
    }
    // With a reactance X the aliases θ + 2πk get +X and their mirrors 2πk - θ get -X.
    const double target = 3.0;
    const OperatorModel tuned = alias_tuned_operator(kPen, theta, kRateHz, 4, target);
    const double first = theta * kRateHz, mirror = (2.0 * std::numbers::pi - theta) * kRateHz;
    for (auto [omega, expected] : {std::pair{first, target}, {mirror, -target}}) {
        double x =
            (kPen.mass_kg + tuned.hand_mass_kg) * omega - tuned.hand_stiffness_n_per_m / omega;
        for (const OperatorMode& mode : tuned.modes) {
            const double w2 = mode.stiffness_n_per_m / mode.mass_kg;
            x += mode.mass_kg * omega * w2 / (w2 - omega * omega);
        }
        // The truncated tan/cot series keeps its tail as a rigid mass: within 2 %.
        EXPECT_NEAR(x, expected, 0.02 * target) << omega;
    }
}

TEST(OperatorSynthesis, WorstEnvironmentHasTheRequestedAdmittance) {
    for (double theta : {0.1, 1.0, 2.5}) {
        for (double h : {-3e-3, 2e-4}) {
            const EnvironmentModel e = lossless_environment_with_admittance(theta, kRateHz, h);
            EXPECT_GT(e.mass_kg, 0.0);
            EXPECT_GT(e.stiffness_n_per_m, 0.0);
            EXPECT_EQ(e.damping_n_s_per_m, 0.0);
            const double reactance = e.mass_kg * 2.0 * kRateHz * std::tan(theta / 2.0) -
                                     e.stiffness_n_per_m / (2.0 * kRateHz * std::tan(theta / 2.0));
            EXPECT_NEAR(-1.0 / reactance, h, 1e-9 * std::abs(h));
        }
    }
}

}  // namespace
}  // namespace hapticd::tune
