// Operator classes and scenes (tune/operator_class.hpp, tune/class_check.hpp,
// tune/environment_assumption.hpp): what a class and a scene buy, that the class search
// climbs to the worst member a class holds, and that the scene bound is reached.
#include "hapticd/tune/class_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "operator_classes.hpp"

namespace hapticd::tune {
namespace {

using theory::DeviceModel;
using theory::SpringDamperCoupling;

const DeviceModel kPen{0.1, 2.0};  // m = 0.1 kg, b = 2 N s/m
constexpr double kRateHz = 1000.0;
constexpr double kPeriodS = 1.0 / kRateHz;

OperatorClass pen_grip() { return testing::pen_grip_class(); }

StabilityAssumption for_class(const OperatorClass& c) { return {c, {}}; }

StabilityAssumption rigid_wall_scene() {
    StabilityAssumption a;
    a.environments.scene = {{EnvironmentModel::rigid_wall(), "a proxy plane in contact"}};
    a.environments.scene_name = "test";
    return a;
}

std::string message_of(const OperatorClass& c) {
    try {
        validate(c, "lab.toml: [operator]");
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

TEST(OperatorClass, MembersSpanTheDeclaredRanges) {
    const OperatorClass c = pen_grip();
    const OperatorModel low = c.member({0, 0, 0, 0, 0});
    const OperatorModel high = c.member({1, 1, 1, 1, 1});
    EXPECT_EQ(low.family, OperatorFamily::two_mass_grasp);
    EXPECT_DOUBLE_EQ(low.hand_mass_kg, 0.1);
    EXPECT_DOUBLE_EQ(low.skin_stiffness_n_per_m, 0.0);
    EXPECT_DOUBLE_EQ(low.skin_damping_n_s_per_m, 2.0);
    EXPECT_DOUBLE_EQ(high.hand_mass_kg, 2.0);
    EXPECT_DOUBLE_EQ(high.skin_stiffness_n_per_m, 3000.0);
    EXPECT_DOUBLE_EQ(high.arm_damping_n_s_per_m, 20.0);
    // A range over a decade is logarithmic: the middle of 0.1..2 kg is sqrt(0.2).
    EXPECT_NEAR(c.member({0.5, 0, 0, 0, 0}).hand_mass_kg, std::sqrt(0.2), 1e-12);
    // From 0, half the points lie in the lowest 3 %.
    EXPECT_NEAR(c.member({0, 0.5, 0, 0, 0}).skin_stiffness_n_per_m,
                3000.0 * (std::sqrt(1000.0) - 1.0) / 999.0, 1e-9);
    EXPECT_TRUE(c.contains(high));
    EXPECT_TRUE(c.contains(OperatorModel::hands_off()));
    EXPECT_FALSE(c.contains(OperatorModel::two_mass_grasp(3001.0, 2.0, 1.0, 0.0, 0.0)));
    EXPECT_FALSE(c.contains(OperatorModel::heavy_hand(1.0, 0.0)));
}

TEST(OperatorClass, BadOrContradictoryClassesNameTheKeyAndTheRange) {
    OperatorClass c = pen_grip();
    c.grip_damping_n_s_per_m = {30.0, 2.0};
    EXPECT_NE(message_of(c).find("lab.toml: [operator] grip_damping = [30, 2] is an empty range"),
              std::string::npos)
        << message_of(c);
    c = pen_grip();
    c.hand_mass_kg = {0.0, 2.0};
    EXPECT_NE(
        message_of(c).find("hand_mass = 0 kg is out of range: allowed >= 1e-06 kg and <= 1000 kg"),
        std::string::npos)
        << message_of(c);
    c = pen_grip();
    c.arm_stiffness_n_per_m.max = std::nan("");
    EXPECT_NE(message_of(c).find("arm_stiffness = nan N/m is out of range"), std::string::npos)
        << message_of(c);
    c = pen_grip();
    c.grip_stiffness_n_per_m = {100.0, 3e7};
    EXPECT_NE(message_of(c).find("grip_stiffness = 3e+07 N/m is out of range"), std::string::npos)
        << message_of(c);
    // The softest, heaviest hand: sqrt((500 + 0)/2)/(2π) = 2.52 Hz, above a 2 Hz bound.
    c = pen_grip();
    c.grip_stiffness_n_per_m.min = 500.0;
    c.max_resonance_hz = 2.0;
    EXPECT_NE(message_of(c).find("max_resonance = 2 Hz contradicts the ranges"), std::string::npos)
        << message_of(c);
    c.max_resonance_hz = 3.0;
    EXPECT_EQ(message_of(c), "");
    EXPECT_EQ(message_of(pen_grip()), "");
}

TEST(ClassCheck, TheClassBuysStiffnessWhereTheCouplingDampingWorks) {
    // At b_c = 1 the passive bound is 2(b - b_c)/T = 2000 N/m; hands like the pen grip's
    // hold more than twice that, and the limit's rejection names a member of the class.
    const StiffnessLimit limit =
        exact_stiffness_limit(kPen, {0.0, 1.0}, kRateHz, for_class(pen_grip()), 0.0);
    EXPECT_GT(limit.stiffness_n_per_m, 2.5 * 2000.0);
    EXPECT_LT(limit.stiffness_n_per_m, 1e4);
    EXPECT_TRUE(limit.at_limit.stable);
    const ExactCheck rejected =
        check_exact(kPen, {limit.rejected_n_per_m, 1.0}, kRateHz, for_class(pen_grip()), 0.0);
    EXPECT_FALSE(rejected.stable);
    EXPECT_TRUE(pen_grip().contains(rejected.worst_operator)) << rejected.worst_operator.describe();
    // The same gains fail for every passive operator.
    EXPECT_FALSE(theory::check_coupling(kPen, {limit.stiffness_n_per_m, 1.0},
                                        theory::HoldModel::passive, kRateHz)
                     .unconditionally_stable);
}

TEST(ClassCheck, TheSearchClimbsToAStiffGripTunedToNyquist) {
    // A class wide enough to hold the steel grip tuned to Nyquist: a heavy hand behind a
    // lossless grip of k_s ~ m (π/T)² = 9.87e5 N/m is, at Nyquist, a spring to ground that
    // cancels the device's mass there. A single-mode operator, so the limit is the one
    // resonance's, k_c T/2 + b_c < (π²/8) b (docs/stability-models.md), at b_c = 1:
    // 2 ((π²/8) 2 - 1)/T = 2935 N/m. No grid point sits on the resonance; the climb must
    // find it.
    OperatorClass wide;
    wide.hand_mass_kg = {1.0, 100.0};
    wide.grip_stiffness_n_per_m = {1e4, 1e7};
    wide.grip_damping_n_s_per_m = {0.0, 0.0};
    wide.arm_stiffness_n_per_m = {0.0, 0.0};
    wide.arm_damping_n_s_per_m = {0.0, 0.0};
    const double single_mode_limit =
        2.0 * (std::numbers::pi * std::numbers::pi / 8.0 * 2.0 - 1.0) / kPeriodS;
    StabilityAssumption a = for_class(wide);
    a.environments = rigid_wall_scene().environments;
    const ExactCheck above = check_exact(kPen, {1.01 * single_mode_limit, 1.0}, kRateHz, a, 0.0);
    EXPECT_FALSE(above.stable);
    EXPECT_NEAR(above.worst_frequency_hz, 500.0, 1.0);
    EXPECT_TRUE(wide.contains(above.worst_operator));
    // The passive bound (2000 N/m here) is for every operator; this class stops short of it.
    EXPECT_TRUE(check_exact(kPen, {0.99 * single_mode_limit, 1.0}, kRateHz, a, 0.0).stable);
}

TEST(ClassCheck, NoRandomMemberBeatsTheSearch) {
    // At 0.999 of the class limit, 300 random members (and hands-off) against the rigid wall
    // and the default environments are all stable: the search found the worst of them.
    const OperatorClass c = pen_grip();
    const StiffnessLimit limit =
        exact_stiffness_limit(kPen, {0.0, 0.5}, kRateHz, for_class(c), 1.0);
    const SpringDamperCoupling coupling{0.999 * limit.stiffness_n_per_m, 0.5};
    std::mt19937 random(9);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<OperatorModel> members;
    members.reserve(300);
    for (int i = 0; i < 300; ++i) {
        members.push_back(
            c.member({unit(random), unit(random), unit(random), unit(random), unit(random)}));
    }
    const ExactCheck random_check =
        check_exact(kPen, coupling, kRateHz, members, default_environment_sweep(kPen), 1.0);
    EXPECT_TRUE(random_check.stable) << random_check.worst_operator.describe();
    EXPECT_LE(random_check.worst_spectral_radius,
              check_exact(kPen, coupling, kRateHz, for_class(c), 1.0).worst_spectral_radius);
}

TEST(ClassCheck, HandsOffMeetsTheLosslessMassWorstForIt) {
    // Found by a hostile tester with an independent model (tools/scripts/class_adversary.py):
    // with one period of delay, the device alone against a lossless virtual mass of about its
    // own mass on a vanishing spring grows by |z| = 1.000016 per tick at 1010 N/m and b_c = 0,
    // and by 1.0000162 at 1618.8 N/m and b_c = 0.5 (a 0.42 kg mass). Hands-off is in every
    // class, so the class check must reject both; the first version called them stable.
    for (const auto& [k, bc] : {std::pair{1010.0, 0.0}, std::pair{1618.8184, 0.5}}) {
        const ExactCheck c = check_exact(kPen, {k, bc}, kRateHz, for_class(pen_grip()), 1.0);
        EXPECT_FALSE(c.stable) << k;
        EXPECT_EQ(c.worst_operator.family, OperatorFamily::hands_off) << k;
        EXPECT_EQ(c.worst_environment.kind, EnvironmentModel::Kind::lossless_mass_spring) << k;
        EXPECT_GT(c.worst_spectral_radius, 1.00001) << k;
    }
}

/// The largest k_c at b_c that check_passive_scene accepts.
double scene_limit(const StabilityAssumption& a, double bc, double delay_periods) {
    double lo = 0.0, hi = 1e5;
    while (hi - lo > 1e-7 * hi) {
        const double mid = 0.5 * (lo + hi);
        const bool stable =
            check_passive_scene(kPen, {mid, bc}, kRateHz, a.environments.scene, delay_periods)
                .stable;
        (stable ? lo : hi) = mid;
    }
    return lo;
}

TEST(SceneCheck, ARigidWallSceneBuysStiffnessOnlyWithADelay) {
    const StabilityAssumption wall = rigid_wall_scene();
    // No delay: the rigid wall is the worst passive environment, k_c T/2 + b_c <= b.
    EXPECT_NEAR(scene_limit(wall, 0.5, 0.0), 2.0 * 1.5 / kPeriodS, 1e-3);
    // One period: the heavy-hand limit 2(b + b_c)/(T(1 + 2d)) at b_c = 0, 1333 N/m, against
    // the passive bound over every environment, b/(2T) = 1000 N/m.
    EXPECT_NEAR(scene_limit(wall, 0.0, 1.0), 2.0 * 2.0 / (kPeriodS * 3.0), 1e-2);
}

TEST(SceneCheck, TheExactModelReachesTheSceneBound) {
    // The scene bound holds for every passive operator: the alias-tuned operators built for
    // the scene's environments reach it (1.03x unstable), and nothing is unstable below it.
    // At a fraction of a period the operators shaped alias by alias towards the rim point
    // nearest each environment do (operator_synthesis.hpp); the same-reactance ones did not.
    StabilityAssumption virtual_mass;
    virtual_mass.environments.scene = {
        {EnvironmentModel::mass_spring(0.5, 20.0, 1.0), "[virtual_mass]"},
        {EnvironmentModel::rigid_wall(), "[virtual_mass] in contact"}};
    virtual_mass.environments.scene_name = "virtual-mass";
    for (const StabilityAssumption& a : {rigid_wall_scene(), virtual_mass}) {
        for (const double delay : {0.0, 0.5, 1.0, 1.25}) {
            for (const double bc : {0.0, 0.6}) {
                SCOPED_TRACE(::testing::Message()
                             << a.environments.describe() << ", delay " << delay << ", b_c " << bc);
                const double k = scene_limit(a, bc, delay);
                EXPECT_FALSE(check_exact(kPen, {1.03 * k, bc}, kRateHz, a, delay).stable);
                const ExactCheck below = check_exact(kPen, {0.99 * k, bc}, kRateHz, a, delay);
                EXPECT_TRUE(below.stable) << below.worst_operator.describe();
            }
        }
    }
}

TEST(SceneCheck, ASceneIsNeverWorseThanEveryPassiveEnvironment) {
    StabilityAssumption wall_and_spring;
    wall_and_spring.environments.scene = {
        {EnvironmentModel::mass_spring(0.0, 2e4, 5.0), "[[wall]] #1"},
        {EnvironmentModel::mass_spring(0.0, 100.0, 0.0), "[[spring]] #1"}};
    for (const double delay : {0.0, 0.5, 1.0, 2.0}) {
        for (const double bc : {0.0, 0.3, 1.0}) {
            double passive = 0.0, hi = 1e5;  // the bound over every passive environment
            while (hi - passive > 1e-7 * hi) {
                const double mid = 0.5 * (passive + hi);
                (theory::check_coupling(kPen, {mid, bc}, {theory::HoldModel::passive, delay},
                                        kRateHz)
                         .unconditionally_stable
                     ? passive
                     : hi) = mid;
            }
            EXPECT_GE(scene_limit(wall_and_spring, bc, delay), passive * (1.0 - 1e-6))
                << "delay " << delay << ", b_c " << bc;
        }
    }
}

}  // namespace
}  // namespace hapticd::tune

namespace hapticd::tune {
namespace {

// Issue 27, item 1: a class whose members reach two aliases of Nyquist at once. The search that
// moved one parameter at a time certified 3929.69 N/m at b_c = 0.5; a member (hand 0.1 kg, grip
// 3,773,027 N/m, arm 2,323,550 N/m, lossless: free-handle modes at 500 and 1500 Hz) grows by
// 1.000658 per tick there. The search now places two modes on two aliases at once (solving
// det(K - ω² M) = 0 for k_s and k_a) and stops at the two-mode limit
// b_c + k_c T/2 < (π²/8) b / S_2, 3441 N/m.
TEST(ClassSearch, FindsTwoModesTunedTogether) {
    const OperatorClass wide = testing::stiff_grips_class();
    const StabilityAssumption a = for_class(wide);
    const OperatorModel member = OperatorModel::two_mass_grasp(3773027.0, 0.0, 0.1, 2323550.0, 0.0);
    ASSERT_TRUE(wide.contains(member));
    const SpringDamperCoupling old_answer{3929.69, 0.5};
    ExactCheck alone =
        check_exact(kPen, old_answer, kRateHz, {member}, default_environment_sweep(kPen), 0.0);
    EXPECT_GT(alone.worst_spectral_radius, 1.0005);
    const ExactCheck search = check_exact(kPen, old_answer, kRateHz, a, 0.0);
    EXPECT_FALSE(search.stable) << search.worst_operator.describe();
    EXPECT_EQ(search.worst_operator.family, OperatorFamily::two_mass_grasp);
    const double two_modes = std::numbers::pi * std::numbers::pi / 8.0 * 2.0 / (1.0 + 1.0 / 9.0);
    const double limit = (two_modes - 0.5) * 2.0 * kRateHz;  // 3441 N/m
    EXPECT_NEAR(limit, 3441.0, 1.0);
    const StiffnessLimit sized = exact_stiffness_limit(kPen, {0.0, 0.5}, kRateHz, a, 0.0);
    EXPECT_LE(sized.stiffness_n_per_m, limit * 1.002);
    EXPECT_GE(sized.stiffness_n_per_m, 0.97 * limit);
}

/// SearchFor::witness checks the cases built for the design first and ends at the first
/// that grows by kDecisiveGrowthPerTick; where nothing grows it is the worst-case search.
TEST(WitnessSearch, AgreesWithTheWorstCaseSearchAndStopsAtTheFirstGrowth) {
    const theory::DeviceModel pen{0.1, 2.0};
    const double rate_hz = 1000.0;
    for (const double delay_periods : {0.0, 2.0}) {
        // At the passive bound (proven: nothing grows) and 3 % past it.
        ImpedanceSizingRequest request;
        request.device = pen;
        request.rate_hz = rate_hz;
        request.model = {theory::HoldModel::passive, delay_periods};
        request.coupling_damping_n_s_per_m = 0.5;
        const theory::SpringDamperCoupling limit = size_impedance_coupling(request).coupling;
        const ExactCheck worst = check_exact(pen, limit, rate_hz, delay_periods);
        const ExactCheck witness =
            check_exact(pen, limit, rate_hz, delay_periods, SearchFor::witness);
        EXPECT_TRUE(worst.stable) << delay_periods;
        EXPECT_EQ(witness.cases_checked, worst.cases_checked) << delay_periods;
        EXPECT_EQ(witness.worst_spectral_radius, worst.worst_spectral_radius) << delay_periods;

        theory::SpringDamperCoupling past = limit;
        past.stiffness_n_per_m *= 1.03;
        const ExactCheck all = check_exact(pen, past, rate_hz, delay_periods);
        const ExactCheck first = check_exact(pen, past, rate_hz, delay_periods, SearchFor::witness);
        EXPECT_FALSE(all.stable) << delay_periods;
        EXPECT_FALSE(first.stable) << delay_periods;
        EXPECT_TRUE(decisive(first)) << first.worst_spectral_radius;
        EXPECT_LE(first.worst_spectral_radius, all.worst_spectral_radius) << delay_periods;
        EXPECT_LT(first.cases_checked * 10, all.cases_checked) << delay_periods;
        // The witness named is a case that grows: checked again on its own.
        const ClosedLoopPoles again = closed_loop_poles(pen, past, rate_hz, first.worst_operator,
                                                        first.worst_environment, delay_periods);
        EXPECT_DOUBLE_EQ(again.spectral_radius, first.worst_spectral_radius);
    }
}

}  // namespace
}  // namespace hapticd::tune
