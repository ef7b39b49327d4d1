// The force sensor's anti-aliasing filter (force_sensor_filter.hpp) and (P2) with it
// (admittance_passive.hpp): closed forms against alias sums, the tails, and the margin.
#include "hapticd/theory/force_sensor_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "hapticd/theory/admittance_passive.hpp"

namespace hapticd::theory {
namespace {

constexpr double kT = 1e-3;
constexpr double kPi = std::numbers::pi;

// The matrix-exponential hold equivalent is the alias sum (1 - e^{-jθ}) Σ H_k e^{-jθ_k φ}/(jθ_k)
// (terms ~ 1/k³), for under-, critically and over-damped filters and a fractional delay.
TEST(ForceSensorFilter, TheHoldEquivalentIsTheAliasSum) {
    for (const double zeta : {0.3, 1.0, 3.0}) {
        for (const double phi : {0.0, 0.4}) {
            const ForceSensorFilter f{120.0, zeta, 2};
            for (const double theta : {0.05, 1.0, 3.0}) {
                Complex sum = 0.0;
                for (int k = -200000; k <= 200000; ++k) {
                    const double tk = theta + 2.0 * kPi * k;
                    sum += force_filter_response(f, tk / kT) * std::polar(1.0, -tk * phi) /
                           Complex(0.0, tk);
                }
                sum *= 1.0 - std::polar(1.0, -theta);
                EXPECT_NEAR(std::abs(force_filter_hold_equivalent(f, theta, kT, phi) - sum), 0.0,
                            1e-9)
                    << "ζ " << zeta << " φ " << phi << " θ " << theta;
            }
        }
    }
}

// Far above the rate the filter is a wire and the sample is the held force at nT⁻: z^{-1}.
TEST(ForceSensorFilter, AVeryFastFilterReadsTheHeldForce) {
    const ForceSensorFilter f{100.0 / kT, 0.7071067811865476, 2};
    for (const double theta : {0.1, 2.0}) {
        EXPECT_NEAR(std::abs(force_filter_hold_equivalent(f, theta, kT) - std::polar(1.0, -theta)),
                    0.0, 1e-9);
    }
}

// Order 2: the partial sums converge and the tail bound covers what is left. Order 1: they
// grow like 2 (f_aa/f_s) ln(terms): Σ|β_k| diverges and no coupling is sized.
TEST(ForceSensorFilter, TheAliasSumConvergesForOrderTwoOnly) {
    const ForceSensorFilter second{100.0, 0.7071067811865476, 2};
    const double at_64 = force_filter_alias_sum(second, 1.0, kT, 64);
    const double at_4096 = force_filter_alias_sum(second, 1.0, kT, 4096);
    const FilterAliasTail tail = force_filter_alias_tail(second, kT, 64);
    EXPECT_GT(at_4096, at_64);
    EXPECT_LE(at_4096 - at_64, tail.response);
    EXPECT_LT(tail.response, 2.0 * (at_4096 - at_64) + 1e-6);  // the bound is not loose
    const ForceSensorFilter first{100.0, 0.7071067811865476, 1};
    const double growth = force_filter_alias_sum(first, 1.0, kT, 10000) -
                          force_filter_alias_sum(first, 1.0, kT, 1000);
    EXPECT_NEAR(growth, 2.0 * 100.0 * kT * std::log(10.0), 1e-3);
    EXPECT_TRUE(std::isinf(force_filter_alias_tail(first, kT, 64).response));
    const FilteredAliasMargin m = filtered_alias_margin(
        {2.0, 5.0}, {2.0, 0.0}, first, environment_admittance_disk({INFINITY, 300.0}, 1.0, kT), 1.0,
        kT, 0.0);
    EXPECT_TRUE(std::isinf(m.margin) && m.margin < 0.0);
}

TEST(ForceSensorFilter, BadInputNamesTheValueAndTheRange) {
    const auto message = [](ForceSensorFilter f) {
        try {
            check_force_sensor_filter(f, 1000.0);
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message({0.0}).find("f_aa = 0 Hz is outside (0, 100000] Hz"), std::string::npos);
    EXPECT_NE(message({100.0, 0.0}).find("ζ = 0 is outside (0, 10]"), std::string::npos);
    EXPECT_NE(message({100.0, 0.7, 3}).find("order 3"), std::string::npos);
    EXPECT_EQ(message({100.0}), "no error");
}

// The branch and bound's certified minimum is below the disk's rigid-wall and free-space
// points, and within its tolerance (and the tails' allowance) of the best point it found.
TEST(FilteredAliasMargin, TheBranchAndBoundMinimumIsCertified) {
    const DeviceModel arm{2.0, 5.0};
    const ForceSensorFilter f{100.0, 0.7071067811865476, 2};
    for (const double theta : {0.02, 0.45, 2.5}) {
        for (const MassDamperCoupling c :
             {MassDamperCoupling{INFINITY, 200.0}, MassDamperCoupling{5.0, INFINITY}}) {
            const EnvironmentAdmittanceDisk disk = environment_admittance_disk(c, theta, kT);
            const FilteredAliasMargin m =
                filtered_alias_margin(arm, {2.0, 0.0}, f, disk, theta, kT, 0.0);
            // Free space (2 × the centre) and the rigid wall (0): tiny disks there.
            for (const double y : {1e-13 * disk.radius, 2.0 * disk.centre}) {
                const FilteredAliasMargin point = filtered_alias_margin(
                    arm, {2.0, 0.0}, f, {y, 1e-12 * disk.radius}, theta, kT, 0.0);
                EXPECT_LE(m.value_at_worst, point.value_at_worst + 1e-7) << theta;
            }
            // Free space and the rigid wall are points of the disk: the minimum is below both.
            EXPECT_LE(m.margin, m.value_at_worst);
            EXPECT_LE(m.value_at_worst - m.margin, 1e-2);  // the tolerance and the tails
            EXPECT_LE(std::abs(m.worst_admittance - disk.centre), disk.radius * (1.0 + 1e-12));
        }
    }
}

// The rigid wall alone (a disk shrunk to Y = 0) is (P1): |1 - ζ/(2b)| - |ζ|/(2b), ζ = -K e^{-jθ}.
TEST(FilteredAliasMargin, AtTheRigidWallItIsTheVelocityLoopCondition) {
    const DeviceModel arm{2.0, 5.0};
    const ForceSensorFilter f{100.0, 0.7071067811865476, 2};
    for (const double theta : {0.3, 1.7, kPi}) {
        const Complex zeta = -pi_gain({2.0, 0.0}, theta, kT) * std::polar(1.0, -theta);
        const double expected = std::abs(1.0 - zeta / 10.0) - std::abs(zeta) / 10.0;
        const FilteredAliasMargin m =
            filtered_alias_margin(arm, {2.0, 0.0}, f, {1e-15, 1e-15}, theta, kT, 0.0);
        // The first 64 aliases' sums: above the whole sum's value by at most the tails.
        EXPECT_GE(m.value_at_worst, expected - 1e-12) << theta;
        EXPECT_LT(m.value_at_worst, expected + 2e-3) << theta;
        EXPECT_LE(m.margin, expected);
        EXPECT_GT(m.margin, expected - 1e-3);  // the tails' allowance
    }
}

// As θ -> 0 the large-|Y| slope is -θ |K| (m/(2bT)) Σ_{k≠0} |H(j2πk/T)|, and a finite coupling
// mass lets |Y_v| reach 2T/(m_c θ²): every pure mass fails at low enough frequency.
TEST(FilteredAliasMargin, EveryFiniteCouplingMassFailsAtLowFrequency) {
    const DeviceModel arm{2.0, 5.0};
    const ForceSensorFilter f{100.0, 0.7071067811865476, 2};
    double aliases = 0.0;
    for (int k = 1; k <= 100000; ++k)
        aliases += 2.0 * std::abs(force_filter_response(f, 2.0 * kPi * k / kT));
    const double theta = 1e-6;
    const double expected = -theta * 2.0 * (2.0 / (2.0 * 5.0 * kT)) * aliases;
    EXPECT_NEAR(filtered_alias_slope(arm, {2.0, 0.0}, f, theta, kT, 0.0) / expected, 1.0, 0.02);
    // m_c = 1000 kg at 1e-5 rad: a point of the disk (a spring resonating with it) fails.
    const MassDamperCoupling heavy{1000.0, INFINITY};
    EXPECT_LT(filtered_alias_margin(arm, {2.0, 0.0}, f,
                                    environment_admittance_disk(heavy, 1e-5, kT), 1e-5, kT, 0.0)
                  .value_at_worst,
              -1.0);
    const FilteredPassiveCheck check =
        check_filtered_admittance_passive(arm, {2.0, 0.0}, f, heavy, kT, 0.0);
    EXPECT_TRUE(check.fails_at_dc);
    EXPECT_FALSE(check.holds);
    // A pure damper's disk is bounded (|Y_v| <= 1/b_c): it holds when b_c is large enough.
    EXPECT_TRUE(
        check_filtered_admittance_passive(arm, {2.0, 0.0}, f, {INFINITY, 400.0}, kT, 0.0).holds);
    EXPECT_FALSE(
        check_filtered_admittance_passive(arm, {2.0, 0.0}, f, {INFINITY, 100.0}, kT, 0.0).holds);
}

}  // namespace
}  // namespace hapticd::theory
