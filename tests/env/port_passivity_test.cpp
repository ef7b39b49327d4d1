// The passivity controller on an external world's port (env/port_passivity.hpp): against worlds
// that try to extract energy every way they can (random jumps, steps against the force, steps
// timed to the handle's motion), over random gains, periods and handle motions, the energy the
// port has absorbed, recomputed from the outside with the coupling's own force (16), never goes
// below zero; a step the world can afford is taken as it is; a step it cannot is replaced by the
// nearest it can, which no sampled feasible step beats; observe books and never changes a step.
#include "hapticd/env/port_passivity.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <random>

namespace hapticd::env {
namespace {

struct Case {
    CouplingGains gains;
    double period_s = 1e-3;
};

// The coupling's force on the tool (16) at the tool `tool_m`, one tick after `previous_m`.
Vec3 coupling_force(const Case& c, const Vec3& x_d, const Vec3& v_d, const Vec3& tool_m,
                    const Vec3& previous_m) {
    return c.gains.stiffness_n_per_m * (x_d - tool_m) +
           c.gains.damping_n_s_per_m * (v_d - (tool_m - previous_m) / c.period_s);
}

Vec3 random_vector(std::mt19937_64& rng, double scale) {
    std::normal_distribution<double> n(0.0, scale);
    return {n(rng), n(rng), n(rng)};
}

// The world's adversarial wish at a tick: one of several ways to take energy out.
Vec3 adversary(std::mt19937_64& rng, const Case& c, const Vec3& x_d, const Vec3& v_d,
               const Vec3& previous_m) {
    const Vec3 f0 =
        c.gains.stiffness_n_per_m * (x_d - previous_m) + c.gains.damping_n_s_per_m * v_d;
    const double kappa = c.gains.stiffness_n_per_m + c.gains.damping_n_s_per_m / c.period_s;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    switch (rng() % 5) {
        case 0:  // a jump anywhere
            return previous_m + random_vector(rng, 0.01);
        case 1:  // against the force, by up to ten times the ball
            return previous_m - (10.0 * u(rng)) * f0 / std::max(kappa, 1e-9);
        case 2:  // just past the ball's edge along the force
            return previous_m + (1.0 + 1e-6 + u(rng)) * f0 / std::max(kappa, 1e-9);
        case 3:  // stay behind while the handle moves on (a hold)
            return previous_m;
        default:  // onto the handle and beyond it
            return x_d + u(rng) * (x_d - previous_m) + random_vector(rng, 1e-4);
    }
}

Case random_case(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Case c;
    c.gains.stiffness_n_per_m = rng() % 4 == 0 ? 0.0 : std::pow(10.0, 1.0 + 4.0 * u(rng));
    c.gains.damping_n_s_per_m = rng() % 3 == 0 ? 0.0 : std::pow(10.0, -1.0 + 3.0 * u(rng));
    c.period_s = (1.0 + static_cast<double>(rng() % 3)) * (rng() % 2 == 0 ? 1e-3 : 2.5e-4);
    return c;
}

TEST(EnvPortPassivity, NoWorldGetsNetEnergyOutOfThePortWhateverItWants) {
    std::mt19937_64 rng(20261207);
    int acted = 0;
    for (int world = 0; world < 300; ++world) {
        const Case c = random_case(rng);
        PortPassivity controller(PassivityMode::control);
        Vec3 tool_m = random_vector(rng, 0.01);
        Vec3 x_d = tool_m;
        double outside_energy_j = 0.0;
        for (int tick = 0; tick < 2000; ++tick) {
            const Vec3 previous_d = x_d;
            x_d += random_vector(rng, 1e-4);
            const Vec3 v_d = (x_d - previous_d) / c.period_s;
            const Vec3 wanted = adversary(rng, c, x_d, v_d, tool_m);
            const Vec3 next = controller.limit(wanted, tool_m, x_d, v_d, c.gains, c.period_s);
            acted += controller.acted() ? 1 : 0;
            const Vec3 f = coupling_force(c, x_d, v_d, next, tool_m);
            outside_energy_j += glm::dot(f, next - tool_m);
            tool_m = next;
            ASSERT_GE(controller.energy_j(), 0.0) << "world " << world << " tick " << tick;
            // The books agree with the energy recomputed from the force, to rounding.
            ASSERT_NEAR(outside_energy_j, controller.energy_j(),
                        1e-9 * (1.0 + std::abs(outside_energy_j)))
                << "world " << world << " tick " << tick;
        }
        EXPECT_GE(controller.removed_j(), 0.0);
    }
    EXPECT_GT(acted, 100000);  // the adversaries did test it
}

TEST(EnvPortPassivity, AStepTheWorldCanAffordIsTakenAsItIs) {
    const Case c{.gains = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 5.0}};
    PortPassivity controller(PassivityMode::control);
    const Vec3 x_d(0.01, 0.0, 0.0);
    const Vec3 previous(0.0);
    // Along the force, inside the ball: the port absorbs energy.
    const Vec3 wanted(0.001, 0.0, 0.0);
    EXPECT_EQ(controller.limit(wanted, previous, x_d, Vec3(0.0), c.gains, c.period_s), wanted);
    EXPECT_FALSE(controller.acted());
    EXPECT_GT(controller.energy_j(), 0.0);
    EXPECT_EQ(controller.removed_j(), 0.0);
}

TEST(EnvPortPassivity, AStepItCannotAffordBecomesTheNearestThatKeepsThePortPassive) {
    std::mt19937_64 rng(7);
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Case c = random_case(rng);
        if (c.gains.stiffness_n_per_m + c.gains.damping_n_s_per_m == 0.0) continue;
        PortPassivity controller(PassivityMode::control);
        const Vec3 previous = random_vector(rng, 0.01);
        controller.reset(previous);  // the world wanted its tool there the tick before
        const Vec3 x_d = previous + random_vector(rng, 0.001);
        const Vec3 v_d = random_vector(rng, 0.1);
        const Vec3 wanted = previous + random_vector(rng, 0.01);
        const Vec3 chosen = controller.limit(wanted, previous, x_d, v_d, c.gains, c.period_s);
        if (!controller.acted()) continue;
        ++checked;
        const double chosen_distance = glm::length(chosen - wanted);
        const auto energy_of = [&](const Vec3& tool) {
            return glm::dot(coupling_force(c, x_d, v_d, tool, previous), tool - previous);
        };
        EXPECT_GE(energy_of(chosen), 0.0);
        EXPECT_LT(energy_of(wanted), 0.0);
        // No feasible step sampled around the chosen one is nearer the wanted one.
        for (int s = 0; s < 2000; ++s) {
            const Vec3 other = chosen + random_vector(rng, 1e-3 * (chosen_distance + 1e-9));
            if (energy_of(other) >= 0.0) {
                ASSERT_GE(glm::length(other - wanted), chosen_distance * (1.0 - 1e-9))
                    << "trial " << trial;
            }
        }
        EXPECT_GT(controller.removed_j(), 0.0);
    }
    EXPECT_GT(checked, 50);
}

TEST(EnvPortPassivity, AWorldAtRestHeldFromWhereItWantsItsToolAddsNothingToTheRemoved) {
    const Case c{.gains = {.stiffness_n_per_m = 3600.0, .damping_n_s_per_m = 2.0}};
    PortPassivity controller(PassivityMode::control);
    controller.reset(Vec3(0.0));
    const Vec3 wish(-0.005, 0.0, 0.0);  // 5 mm behind the tool, against the handle's pull
    Vec3 tool(0.0);
    Vec3 x_d(0.001, 0.0, 0.0);
    tool = controller.limit(wish, tool, x_d, Vec3(0.0), c.gains, c.period_s);  // it jumps
    const double after_the_jump_j = controller.removed_j();
    EXPECT_GT(after_the_jump_j, 0.0);
    for (int n = 0; n < 1000; ++n) {  // the hand trembles; the world stays where it is
        const Vec3 before = x_d;
        x_d.x = 0.001 + 1e-5 * std::sin(0.1 * n);
        tool = controller.limit(wish, tool, x_d, (x_d - before) / c.period_s, c.gains, c.period_s);
        ASSERT_GE(controller.energy_j(), 0.0);
    }
    EXPECT_EQ(controller.removed_j(), after_the_jump_j);
}

TEST(EnvPortPassivity, ObserveBooksTheEnergyAndNeverChangesAStepAndOffDoesNothing) {
    const Case c{.gains = {.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 5.0}};
    const Vec3 x_d(0.01, 0.0, 0.0);
    const Vec3 against(-0.01, 0.0, 0.0);  // against the force: the port would deliver energy
    PortPassivity observe(PassivityMode::observe);
    EXPECT_EQ(observe.limit(against, Vec3(0.0), x_d, Vec3(0.0), c.gains, c.period_s), against);
    EXPECT_FALSE(observe.acted());
    const Vec3 f = coupling_force(c, x_d, Vec3(0.0), against, Vec3(0.0));
    EXPECT_DOUBLE_EQ(observe.energy_j(), glm::dot(f, against));
    EXPECT_LT(observe.energy_j(), 0.0);
    EXPECT_EQ(observe.removed_j(), 0.0);
    PortPassivity off(PassivityMode::off);
    EXPECT_EQ(off.limit(against, Vec3(0.0), x_d, Vec3(0.0), c.gains, c.period_s), against);
    EXPECT_EQ(off.energy_j(), 0.0);
    PortPassivity control(PassivityMode::control);
    // Nothing absorbed yet: the tool may not move against the force at all (the ball's edge
    // passes through the tool, a hair inside it).
    const Vec3 held = control.limit(against, Vec3(0.0), x_d, Vec3(0.0), c.gains, c.period_s);
    EXPECT_NEAR(glm::length(held), 0.0, 1e-10);
    EXPECT_TRUE(control.acted());
    EXPECT_GE(control.energy_j(), 0.0);
    EXPECT_LT(control.energy_j(), 1e-9);
}

TEST(EnvPortPassivity, EnergyAbsorbedIsABudgetTheWorldMaySpendLaterAndAResetForgetsIt) {
    const Case c{.gains = {.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 0.0}};
    PortPassivity controller(PassivityMode::control);
    // Pushed 1 cm along the force by a handle 2 cm ahead: k (0.02) 0.01 - k 0.01^2 = 0.1 J.
    const Vec3 x_d(0.02, 0.0, 0.0);
    Vec3 tool =
        controller.limit(Vec3(0.01, 0.0, 0.0), Vec3(0.0), x_d, Vec3(0.0), c.gains, c.period_s);
    EXPECT_NEAR(controller.energy_j(), 0.1, 1e-12);
    // Back 1 cm against the force costs k (0.01) (-0.01) - k 0.01^2 = -0.2 J: more than it has;
    // the step taken spends the whole budget and no more.
    tool = controller.limit(Vec3(0.0), tool, x_d, Vec3(0.0), c.gains, c.period_s);
    EXPECT_TRUE(controller.acted());
    EXPECT_NEAR(controller.energy_j(), 0.0, 1e-9);  // a hair inside the ball's edge
    EXPECT_GE(controller.energy_j(), 0.0);
    EXPECT_GT(tool.x, 0.0);
    EXPECT_LT(tool.x, 0.01);
    EXPECT_NEAR(controller.removed_j(), 0.1, 1e-9);  // -0.1 taken where -0.2 was asked
    controller.reset(tool);
    EXPECT_EQ(controller.energy_j(), 0.0);
    EXPECT_NEAR(controller.removed_j(), 0.1, 1e-9);
}

}  // namespace
}  // namespace hapticd::env
