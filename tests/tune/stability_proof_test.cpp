// The exact model's verdict rests on a proof (issue 27, docs/stability-models.md): where it
// claims every passive operator it never certifies past the passive port condition, which is
// proven and tight, whatever the delay, the damper's filter or the scene; its search only names
// the operators that break a design. A search's marginal worst case is said to be marginal.
#include <gtest/gtest.h>

#include <string>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/environment_assumption.hpp"
#include "hapticd/tune/stability_check.hpp"
#include "operator_classes.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::SpringDamperCoupling;

const DeviceModel kPen{0.1, 2.0};  // m = 0.1 kg, b = 2 N s/m
constexpr double kRateHz = 1000.0;

StabilityDesign design(const DeviceModel& device, SpringDamperCoupling coupling, double rate_hz,
                       double delay_periods, StabilityModel model = StabilityModel::exact) {
    StabilityDesign d;
    d.device = device;
    d.coupling = coupling;
    d.rate_hz = rate_hz;
    d.delay_s = delay_periods / rate_hz;
    d.model = model;
    return d;
}

/// The passive model's largest k_c at b_c against every passive environment (21).
double passive_limit(const DeviceModel& device, double bc, double delay_periods, double rate_hz,
                     double filter_hz = 0.0) {
    ImpedanceSizingRequest request;
    request.device = device;
    request.rate_hz = rate_hz;
    request.model = {theory::HoldModel::passive, delay_periods};
    request.velocity_filter_hz = filter_hz;
    request.coupling_damping_n_s_per_m = bc;
    return size_impedance_coupling(request).coupling.stiffness_n_per_m;
}

struct Case {
    double delay_periods, bc, filter_hz;
};

class FractionalDelays : public ::testing::TestWithParam<Case> {};
INSTANTIATE_TEST_SUITE_P(Issue27, FractionalDelays,
                         ::testing::Values(Case{0.25, 0.0, 0.0}, Case{0.5, 0.0, 0.0},
                                           Case{0.75, 0.0, 0.0}, Case{1.5, 0.0, 0.0},
                                           Case{0.5, 0.5, 0.0}, Case{0.5, 0.5, 100.0},
                                           Case{0.0, 0.5, 0.0}, Case{1.0, 0.5, 0.0}));

// Item 3: at half a period the exact model certified 1777 N/m against the passive 1600, and
// operators are unstable from 1665. Its verdict now never passes the passive bound.
TEST_P(FractionalDelays, TheExactVerdictNeverPassesThePassiveBound) {
    const Case c = GetParam();
    const double k = passive_limit(kPen, c.bc, c.delay_periods, kRateHz, c.filter_hz);
    const StabilityVerdict past =
        check_stability(design(kPen, {1.01 * k, c.bc, c.filter_hz}, kRateHz, c.delay_periods));
    EXPECT_FALSE(past.passed) << past.describe();
    EXPECT_FALSE(past.proven);
    const StabilityVerdict inside =
        check_stability(design(kPen, {0.99 * k, c.bc, c.filter_hz}, kRateHz, c.delay_periods));
    EXPECT_TRUE(inside.passed) << inside.describe();
    EXPECT_TRUE(inside.proven);
    EXPECT_NE(inside.describe().find("proven by the passive port condition"), std::string::npos);
}

TEST(ExactVerdict, HalfAPeriodIsTheClosedFormLowBand) {
    // τ² = (1.5)² + 1/4 = 2.5: k_c <= 2b/(τ² T) = 1600 N/m, not the naive rotation's 1778 or
    // the old exact model's 1777.
    EXPECT_NEAR(passive_limit(kPen, 0.0, 0.5, kRateHz), 1600.0, 1.0);
    EXPECT_FALSE(check_stability(design(kPen, {1750.0, 0.0}, kRateHz, 0.5)).passed);
}

// Item 3, scenes: against a scene's own objects the exact model's verdict is the passive
// scene bound's.
TEST(ExactVerdict, ASceneAtAFractionOfAPeriodStopsAtThePassiveSceneBound) {
    StabilityAssumption wall;
    wall.environments.scene = {{EnvironmentModel::rigid_wall(), "a proxy plane in contact"}};
    StabilityAssumption virtual_mass;
    virtual_mass.environments.scene = {
        {EnvironmentModel::mass_spring(0.5, 20.0, 1.0), "[virtual_mass]"},
        {EnvironmentModel::rigid_wall(), "[virtual_mass] in contact"}};
    for (const StabilityAssumption& a : {wall, virtual_mass}) {
        for (const double delay : {0.25, 0.5}) {
            double lo = 0.0, hi = 1e5;
            while (hi - lo > 1e-6 * hi) {
                const double mid = 0.5 * (lo + hi);
                (check_passive_scene(kPen, {mid, 0.5}, kRateHz, a.environments.scene, delay).stable
                     ? lo
                     : hi) = mid;
            }
            StabilityDesign past = design(kPen, {1.01 * lo, 0.5}, kRateHz, delay);
            past.assumption = a;
            EXPECT_FALSE(check_stability(past).passed) << a.environments.describe() << delay;
            StabilityDesign inside = design(kPen, {0.99 * lo, 0.5}, kRateHz, delay);
            inside.assumption = a;
            EXPECT_TRUE(check_stability(inside).proven) << a.environments.describe() << delay;
        }
    }
}

// Item 4: 0.35 kg, 3 N s/m, 2 kHz, b_c 0.9: the exact model certified 8554.69 N/m, 1.8 % past
// the bound b_c + k_c T/2 <= b (8400 N/m), with a worst margin of -4e-9 called stable.
TEST(ExactVerdict, NoDelayStopsAtBcPlusHalfKcTAndAMarginalSearchIsSaidMarginal) {
    const DeviceModel device{0.35, 3.0};
    const double rate = 2000.0;
    const double bound = (3.0 - 0.9) * 2.0 * rate;  // 8400 N/m
    EXPECT_NEAR(passive_limit(device, 0.9, 0.0, rate), bound, 1e-3 * bound);
    const StabilityVerdict old_answer = check_stability(design(device, {8554.69, 0.9}, rate, 0.0));
    EXPECT_FALSE(old_answer.passed) << old_answer.describe();
    EXPECT_LT(old_answer.worst_margin, 0.0);
    ASSERT_TRUE(old_answer.exact.has_value());
    if (old_answer.exact->worst_margin < 0.0 && old_answer.exact->stable) {
        EXPECT_TRUE(old_answer.exact->marginal());
        EXPECT_NE(old_answer.describe().find("marginal"), std::string::npos);
    }
    EXPECT_TRUE(check_stability(design(device, {0.99 * bound, 0.9}, rate, 0.0)).proven);

    ExactCheck marginal;
    marginal.stable = true;
    marginal.worst_margin = -9e-9;
    EXPECT_TRUE(marginal.marginal());
    marginal.worst_margin = 0.0;
    EXPECT_FALSE(marginal.marginal());
}

// Item 5: near z = 1 (a heavy, lightly damped device at a high rate) the exact sizing returned
// 0 N/m and the class version rejected a provably passive design.
TEST(ExactVerdict, HeavyLightlyDampedFastDevicesGetThePassiveBound) {
    struct Heavy {
        DeviceModel device;
        double rate;
    };
    for (const Heavy h : {Heavy{{6.0, 0.3}, 10000.0}, Heavy{{1000.0, 1e-4}, 100.0}}) {
        const double bound = 2.0 * h.device.damping_n_s_per_m * h.rate;  // 2b/T
        EXPECT_NEAR(passive_limit(h.device, 0.0, 0.0, h.rate), bound, 1e-3 * bound);
        EXPECT_TRUE(check_stability(design(h.device, {0.98 * bound, 0.0}, h.rate, 0.0)).proven)
            << h.device.mass_kg;
        EXPECT_FALSE(check_stability(design(h.device, {1.02 * bound, 0.0}, h.rate, 0.0)).passed)
            << h.device.mass_kg;
    }
    // The class version: k_c = 10, b_c = 0.29 is passive (0.29 + 10 T/2 < 0.3).
    StabilityDesign d = design({6.0, 0.3}, {10.0, 0.29}, 10000.0, 0.0);
    d.assumption.operators = testing::pen_grip_class();
    const StabilityVerdict v = check_stability(d);
    EXPECT_TRUE(v.passed) << v.describe();
    EXPECT_TRUE(v.proven);
}

}  // namespace
}  // namespace hapticd::tune
