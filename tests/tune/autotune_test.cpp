// tune::autotune, the computing half of `haptic-tune autotune`: simulated runs in, verified
// gains out. The config writing is tested end to end in tests/cli/autotune_cli_test.cpp.
#include "hapticd/tune/autotune.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "identification_sim_run.hpp"

namespace hapticd::tune {
namespace {

using testing::simulated_log;
using testing::SimulatedRun;

/// haptic-tune size's own function: the passive bound at b_c = 0.
double passive_bound(const theory::DeviceModel& device, double rate_hz) {
    ImpedanceSizingRequest request;
    request.device = device;
    request.rate_hz = rate_hz;
    request.model = theory::HoldModel::passive;
    request.coupling_damping_n_s_per_m = 0.0;
    return size_impedance_coupling(request).coupling.stiffness_n_per_m;
}

/// A hand-made identification result (for the sizing and verification steps alone).
IdentifiedAxis identified(int axis, double mass_kg, double damping_n_s_per_m,
                          double relative_std_error = 0.002) {
    IdentifiedAxis a;
    a.axis = axis;
    a.estimate = {mass_kg, damping_n_s_per_m, 0.1, 0.0};
    a.std_error = {relative_std_error * mass_kg, relative_std_error * damping_n_s_per_m, 0.01,
                   0.01};
    for (int i = 0; i < 4; ++i) a.correlation[i][i] = 1.0;
    a.rate_hz = 1000.0;
    a.duration_s = 10.0;
    a.report.converged = true;
    return a;
}

// The sim's pen display (m = 0.1 kg, b = 2 N s/m) with 10 um counts, 0.2 N Coulomb friction,
// a 0.05 N offset and 0.02 N force noise: the identified model within 2 %, and the coupling
// exactly margin x haptic-tune size's bound for the model that is written.
TEST(Autotune, SimulatedRunGivesTheModelAndMarginTimesThePassiveBound) {
    const SimulatedRun run;
    AutotuneOptions options;
    options.rate_hz = 1000.0;
    const AutotuneResult r = autotune(simulated_log(run), options);

    ASSERT_EQ(r.axes.size(), 1u);
    EXPECT_NEAR(r.device.mass_kg, run.mass_kg, 0.02 * run.mass_kg);
    EXPECT_NEAR(r.device.damping_n_s_per_m, run.damping_n_s_per_m, 0.02 * run.damping_n_s_per_m);
    // What is written is the estimate to 6 significant digits.
    EXPECT_NEAR(r.device.mass_kg, r.axes[0].identified.estimate.mass_kg, 5e-6 * run.mass_kg);
    EXPECT_EQ(r.device.mass_kg, r.axes[0].device.mass_kg);

    const double bound = passive_bound(r.device, 1000.0);
    EXPECT_EQ(r.bound.stiffness_n_per_m, bound);
    EXPECT_NEAR(bound, 2.0 * r.device.damping_n_s_per_m * 1000.0, 1e-6 * bound);  // 2b/T
    // margin x bound to 6 significant digits.
    EXPECT_NEAR(r.coupling.stiffness_n_per_m, 0.9 * bound, 5e-6 * 0.9 * bound);
    EXPECT_EQ(r.coupling.damping_n_s_per_m, 0.0);
    EXPECT_EQ(r.margin, 0.9);

    EXPECT_TRUE(r.verified) << r.verdict;
    EXPECT_TRUE(r.axes[0].exact.stable);
    EXPECT_GT(r.axes[0].exact.cases_checked, 60000);
    EXPECT_NE(r.verdict.find("stable on every axis"), std::string::npos) << r.verdict;
    EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();

    // The bound 2b/T depends on b alone, so its standard error is 2 sigma_b / T.
    EXPECT_NEAR(r.axes[0].bound_stiffness_std_error_n_per_m,
                2.0 * 1000.0 * r.axes[0].identified.std_error.damping_n_s_per_m,
                1e-3 * r.axes[0].bound_stiffness_std_error_n_per_m);
}

// The gains are for the servo rate, not the log's: a 1 kHz log sizes a 500 Hz servo.
TEST(Autotune, SizesForTheServoRateNotTheLogRate) {
    AutotuneOptions options;
    options.rate_hz = 500.0;
    const AutotuneResult r = autotune(simulated_log(SimulatedRun{}), options);
    EXPECT_EQ(r.rate_hz, 500.0);
    EXPECT_EQ(r.bound.stiffness_n_per_m, passive_bound(r.device, 500.0));
    EXPECT_NEAR(r.bound.stiffness_n_per_m, 2.0 * r.device.damping_n_s_per_m * 500.0,
                1e-6 * r.bound.stiffness_n_per_m);
    EXPECT_TRUE(r.verified) << r.verdict;
}

// Margin 1 is allowed and still verified: at b_c = 0 the passive bound is the exact one
// (docs/stability-models.md), and k_c is rounded down.
TEST(Autotune, MarginOneIsTheBoundAndTheExactModelAgrees) {
    AutotuneOptions options;
    options.margin = 1.0;
    const AutotuneResult r = autotune({identified(0, 0.1, 2.0)}, options);
    EXPECT_LE(r.coupling.stiffness_n_per_m, r.bound.stiffness_n_per_m);
    EXPECT_GE(r.coupling.stiffness_n_per_m, r.bound.stiffness_n_per_m * (1.0 - 1e-5));
    EXPECT_TRUE(r.verified) << r.verdict;
}

TEST(Autotune, RejectsAMarginOutsideZeroToOne) {
    for (const double margin : {0.0, -0.5, 1.0001, 2.0, std::numeric_limits<double>::quiet_NaN(),
                                std::numeric_limits<double>::infinity()}) {
        AutotuneOptions options;
        options.margin = margin;
        try {
            (void)autotune({identified(0, 0.1, 2.0)}, options);
            ADD_FAILURE() << "margin " << margin << " accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("margin"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("(0, 1]"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW((void)autotune(std::vector<IdentifiedAxis>{}, AutotuneOptions{}),
                 std::invalid_argument);
}

// Several axes: each is sized alone; the smallest bound binds; [device.model] is that
// axis's model; every axis is held against the exact model.
TEST(Autotune, TheAxisWithTheSmallestBoundBinds) {
    const AutotuneResult r =
        autotune({identified(0, 0.1, 2.0), identified(1, 0.3, 1.5), identified(2, 0.05, 3.0)},
                 AutotuneOptions{});
    ASSERT_EQ(r.axes.size(), 3u);
    EXPECT_EQ(r.binding_axis, 1);
    EXPECT_EQ(r.device.mass_kg, 0.3);
    EXPECT_EQ(r.device.damping_n_s_per_m, 1.5);
    EXPECT_NEAR(r.bound.stiffness_n_per_m, 3000.0, 1e-6);
    EXPECT_EQ(r.coupling.stiffness_n_per_m, 2700.0);
    for (const AutotuneAxis& a : r.axes) {
        EXPECT_TRUE(a.exact.stable) << "axis " << a.identified.axis;
        EXPECT_LT(r.coupling.stiffness_n_per_m, a.bound.coupling.stiffness_n_per_m);
    }
    EXPECT_TRUE(r.verified) << r.verdict;

    // Ties: the lowest index.
    const AutotuneResult tie =
        autotune({identified(0, 0.2, 2.0), identified(1, 0.2, 2.0)}, AutotuneOptions{});
    EXPECT_EQ(tie.binding_axis, 0);
}

// Under the passive model the optimised pair is the rigid-wall optimum b_c = 0, k_c = 2b/T
// with no delay (coupling damping buys no guaranteed stiffness), and it is verified at the
// default margin; with half a period of delay the optimum has damping (docs/autotune.md).
TEST(Autotune, OptimisedDampingIsNoneWithoutDelayAndVerifiedWithIt) {
    struct Case {
        double mass_kg, damping_n_s_per_m, rate_hz;
    };
    for (const Case c : {Case{0.1, 2.0, 1000.0}, Case{0.5, 5.0, 2000.0}}) {
        AutotuneOptions options;
        options.optimize_damping = true;
        options.rate_hz = c.rate_hz;
        const AutotuneResult none =
            autotune({identified(0, c.mass_kg, c.damping_n_s_per_m)}, options);
        EXPECT_NEAR(none.coupling.damping_n_s_per_m, 0.0, 1e-6 * c.damping_n_s_per_m);
        EXPECT_NEAR(none.bound.stiffness_n_per_m, 2.0 * c.damping_n_s_per_m * c.rate_hz,
                    1e-6 * c.damping_n_s_per_m * c.rate_hz);
        EXPECT_TRUE(none.verified) << none.verdict;

        options.delay_periods = 0.5;
        const AutotuneResult delayed =
            autotune({identified(0, c.mass_kg, c.damping_n_s_per_m)}, options);
        EXPECT_GT(delayed.coupling.damping_n_s_per_m, 0.2 * c.damping_n_s_per_m);
        EXPECT_LT(delayed.bound.stiffness_n_per_m, none.bound.stiffness_n_per_m);
        EXPECT_TRUE(delayed.verified) << delayed.verdict;
        EXPECT_TRUE(delayed.axes[0].exact.stable);
        EXPECT_EQ(delayed.axes[0].exact.delay_periods, 0.5);
    }
}

// The config's velocity filter goes into the sizing and the exact check: with one period of
// delay the filtered best pair is softer (1240.64 N/m at 0.4670 N s/m on a 100 Hz filter,
// against 1539.60 N/m at 0.5635 unfiltered; docs/stability-models.md).
TEST(Autotune, SizesAndVerifiesWithTheVelocityFilter) {
    AutotuneOptions options;
    options.optimize_damping = true;
    options.delay_periods = 1.0;
    options.velocity_filter_hz = 100.0;
    const AutotuneResult r = autotune({identified(0, 0.1, 2.0)}, options);
    EXPECT_EQ(r.coupling.velocity_filter_hz, 100.0);
    EXPECT_EQ(r.bound.velocity_filter_hz, 100.0);
    EXPECT_NEAR(r.bound.stiffness_n_per_m, 1240.64, 0.01);
    EXPECT_NEAR(r.bound.damping_n_s_per_m, 0.4670, 1e-3);
    EXPECT_TRUE(r.verified) << r.verdict;
    options.velocity_filter_hz = 600.0;  // above Nyquist at 1 kHz
    EXPECT_THROW(options.validate(), std::invalid_argument);
}

TEST(Autotune, RejectsADelayOutsideZeroToTenPeriods) {
    for (double d : {-0.1, 10.0, std::nan("")}) {
        AutotuneOptions options;
        options.delay_periods = d;
        EXPECT_THROW(options.validate(), std::invalid_argument) << d;
    }
}

// A margin that does not cover three standard errors of the bound is reported.
TEST(Autotune, WarnsWhenTheMarginIsWithinThreeStandardErrorsOfTheBound) {
    EXPECT_TRUE(autotune({identified(0, 0.1, 2.0, 0.01)}, AutotuneOptions{}).warnings.empty());
    const AutotuneResult r = autotune({identified(0, 0.1, 2.0, 0.04)}, AutotuneOptions{});
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_NE(r.warnings[0].find("three standard errors"), std::string::npos) << r.warnings[0];
    EXPECT_NE(r.warnings[0].find("4.00 %"), std::string::npos) << r.warnings[0];
    EXPECT_TRUE(r.verified);  // a warning, not a refusal: the point estimate is stable
}

// A log that cannot identify the device is refused with the identification's reason.
TEST(Autotune, ATooShortLogIsRefused) {
    SimulatedRun run;
    run.duration_s = 0.5;
    try {
        (void)autotune(simulated_log(run), AutotuneOptions{});
        ADD_FAILURE() << "a 0.5 s log was accepted";
    } catch (const IdentificationRefused& e) {
        EXPECT_EQ(e.reason(), RefusalReason::too_short) << e.what();
    }
}

TEST(Autotune, RoundsToSignificantDigits) {
    EXPECT_EQ(round_significant(0.10003248, 6), 0.100032);
    EXPECT_EQ(round_significant(1.998889, 6), 1.99889);
    EXPECT_EQ(round_significant(3598.0029, 6, /*down=*/true), 3598.0);
    EXPECT_EQ(round_significant(3598.0099, 6, /*down=*/true), 3598.0);
    EXPECT_EQ(round_significant(3598.0099, 6), 3598.01);
    EXPECT_EQ(round_significant(1234567.8, 6), 1234570.0);
    EXPECT_EQ(round_significant(-0.0123456789, 6), -0.0123457);
    EXPECT_EQ(round_significant(0.0, 6), 0.0);
    EXPECT_EQ(round_significant(4000.0, 6, true), 4000.0);
}

}  // namespace
}  // namespace hapticd::tune
