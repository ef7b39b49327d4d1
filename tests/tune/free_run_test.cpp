// tune::free_run_positions, the model identify's fit chart runs free, against the closed
// form of a mass-damper under a force step, with the loop delay and with friction.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hapticd/tune/open_loop_prediction.hpp"

namespace hapticd::tune {
namespace {

constexpr double kMassKg = 0.1;
constexpr double kDampingNsPerM = 2.0;
constexpr double kPeriodS = 1e-3;
constexpr double kStepN = 0.5;

/// x(t) of m x'' + b x' = F from rest at 0, the step acting from t = 0.
double step_position(double t) {
    if (t <= 0.0) return 0.0;
    const double a = kDampingNsPerM / kMassKg;
    return kStepN / kDampingNsPerM * (t - (1.0 - std::exp(-a * t)) / a);
}

TEST(FreeRun, AForceStepMovesTheMassDamperAsItsClosedForm) {
    const std::vector<double> force(200, kStepN);
    const FreeRunModel model{kMassKg, kDampingNsPerM, 0.0, 0.0};
    const std::vector<double> x = free_run_positions(force, model, kPeriodS, {}, 0.0);
    ASSERT_EQ(x.size(), force.size());
    for (std::size_t n = 0; n < x.size(); n += 37) {
        EXPECT_NEAR(x[n], step_position(static_cast<double>(n) * kPeriodS), 1e-12) << n;
    }
}

TEST(FreeRun, TheDelayShiftsTheStepByWholeAndFractionalPeriods) {
    const std::vector<double> force(200, kStepN);
    const FreeRunModel model{kMassKg, kDampingNsPerM, 0.0, 0.0};
    const HoldDelay delay = split_hold_delay(2.5 * kPeriodS, kPeriodS);
    const std::vector<double> x = free_run_positions(force, model, kPeriodS, delay, 0.0);
    for (std::size_t n = 0; n < x.size(); n += 13) {
        EXPECT_NEAR(x[n], step_position((static_cast<double>(n) - 2.5) * kPeriodS), 1e-12) << n;
    }
}

TEST(FreeRun, CoulombFrictionHoldsTheHandleAndTheOffsetAddsToTheForce) {
    const std::vector<double> force(100, kStepN);
    // F_c above the step: the handle stays put.
    const std::vector<double> stuck =
        free_run_positions(force, {kMassKg, kDampingNsPerM, 0.6, 0.0}, kPeriodS, {}, 0.0);
    EXPECT_EQ(stuck.back(), 0.0);
    // An offset of -F cancels the step exactly.
    const std::vector<double> cancelled =
        free_run_positions(force, {kMassKg, kDampingNsPerM, 0.0, -kStepN}, kPeriodS, {}, 0.0);
    EXPECT_NEAR(cancelled.back(), 0.0, 1e-15);
    EXPECT_THROW(free_run_positions(force, {0.0, 1.0, 0.0, 0.0}, kPeriodS, {}, 0.0),
                 std::invalid_argument);
}

}  // namespace
}  // namespace hapticd::tune
