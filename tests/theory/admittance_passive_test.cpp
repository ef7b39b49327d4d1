// The admittance display's passive model (admittance_passive.hpp): the velocity loop's
// condition at a rigid wall (P1) and the force sensor's aliases (P2).
#include "hapticd/theory/admittance_passive.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "hapticd/theory/passive_model.hpp"

namespace hapticd::theory {
namespace {

constexpr double kT = 1e-3;

// (P1) with no delay is Colgate and Schenkel's virtual wall with B = k_p and K = k_i: the
// device needs b >= k_p + k_i T/2, binding at Nyquist.
TEST(AdmittancePassive, TheVelocityLoopAtARigidWallIsAVirtualWall) {
    for (const PiVelocityLoop loop : {PiVelocityLoop{2.0, 0.0}, PiVelocityLoop{4.0, 3000.0}}) {
        const double expected =
            loop.proportional_gain_n_s_per_m + loop.integral_gain_n_per_m * kT / 2.0;
        EXPECT_NEAR(velocity_loop_damping_bound(loop, kT, 0.0), expected, 1e-12);
        EXPECT_NEAR(velocity_loop_damping_needed(loop, std::numbers::pi, kT, 0.0), expected, 1e-9);
        double grid_max = 0.0;
        for (int i = 1; i <= 1000; ++i) {
            grid_max = std::max(
                grid_max, velocity_loop_damping_needed(loop, std::numbers::pi * i / 1000, kT, 0.0));
        }
        EXPECT_NEAR(grid_max, expected, 1e-9);
    }
    // One period of delay, k_i = 0: Re(-k_p e^{-2jθ}) = -k_p cos 2θ, largest (k_p) at π/2.
    EXPECT_NEAR(velocity_loop_damping_bound({3.0, 0.0}, kT, 1.0), 3.0, 1e-9);
}

// (P2): in free space every coupling, PI gain and delay is reached by some passive operator
// with resonances on the aliases of some frequency (reach >= 0 somewhere), and a heavier
// coupling mass only raises how many resonances that takes.
TEST(AdmittancePassive, NoCouplingHoldsForEveryPassiveOperatorInFreeSpace) {
    std::mt19937 random(20261202);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 40; ++i) {
        const DeviceModel device{0.2 + 5.0 * unit(random), 0.5 + 20.0 * unit(random)};
        const PiVelocityLoop loop{0.01 + 5.0 * unit(random), i % 2 == 0 ? 0.0 : 1e3 * unit(random)};
        const double damping = i % 3 == 0 ? INFINITY : 0.1 + 100.0 * unit(random);
        const MassDamperCoupling coupling{0.01 + 50.0 * unit(random), damping};
        const int delay = i % 4 == 3 ? 1 : 0;
        bool reached = false;
        for (int k = 1; k < 64 && !reached; ++k) {
            const double theta = std::numbers::pi * k / 64;
            reached = free_space_alias_reach(device, loop, coupling, theta, kT, delay).reach >= 0.0;
        }
        EXPECT_TRUE(reached) << "m " << device.mass_kg << " b " << device.damping_n_s_per_m
                             << " k_p " << loop.proportional_gain_n_s_per_m << " k_i "
                             << loop.integral_gain_n_per_m << " m_c " << coupling.mass_kg << " b_c "
                             << coupling.damping_n_s_per_m << " q " << delay;
    }
    const DeviceModel device{2.0, 5.0};
    const PiVelocityLoop loop{2.0, 0.0};
    double previous = 0.0;
    for (double mass : {1.0, 10.0, 100.0}) {
        const AliasReach r =
            free_space_alias_reach(device, loop, {mass, INFINITY}, std::numbers::pi, kT, 0);
        EXPECT_GE(r.reach, 0.0);
        EXPECT_GT(r.resonant_aliases_needed, previous) << mass;
        previous = r.resonant_aliases_needed;
    }
}

// At Nyquist with a pure-mass coupling and k_p alone, β_k = (k_p m/m_c) + k_p s_k is real
// and R = 1: the count is the fewest terms whose sum reaches b, in closed form.
TEST(AdmittancePassive, TheResonanceCountAtNyquistIsAClosedForm) {
    const DeviceModel device{2.0, 5.0};
    const double kp = 2.0, mc = 10.0;
    // Signed aliases ±π, ±3π, ...: s = 4/(π² (2j+1)²) each, twice.
    double sum = 0.0;
    int n = 0;
    for (int j = 0; sum < device.damping_n_s_per_m; ++j) {
        const double s = 4.0 / (std::numbers::pi * std::numbers::pi * (2 * j + 1) * (2 * j + 1));
        for (int twice = 0; twice < 2 && sum < device.damping_n_s_per_m; ++twice) {
            sum += kp * device.mass_kg / mc + kp * s;
            ++n;
        }
    }
    const AliasReach r =
        free_space_alias_reach(device, {kp, 0.0}, {mc, INFINITY}, std::numbers::pi, kT, 0);
    EXPECT_EQ(r.resonant_aliases_needed, n);
    EXPECT_EQ(n, 8);
}

}  // namespace
}  // namespace hapticd::theory
