// Penalty objects against closed forms, against central differences of their own force,
// and for the physics they promise: the wall is unilateral and passive, the detent
// conservative, the friction breaks away at F_s, slides at F_k and dissipates.
#include "hapticd/env/penalty_objects.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <numbers>

#include "hapticd/env/friction.hpp"
#include "test_helpers.hpp"

namespace hapticd::env {
namespace {

using testing::expect_near;
using testing::fd_damping;
using testing::fd_stiffness;
constexpr double kPi = std::numbers::pi;

Wall oblique_wall() { return Wall{glm::normalize(Vec3(1.0, 2.0, 2.0)), 0.01, 2.0e4, 30.0}; }

TEST(EnvWall, ClosedFormInContact) {
    const Wall wall{Vec3(-1.0, 0.0, 0.0), 0.0, 2.0e4, 5.0};  // config/scenes/demo-wall.toml
    // 1 mm into the wall (x > 0), approaching at 0.1 m/s.
    const PenaltyForce f = wall.evaluate(Vec3(0.001, 0.0, 0.0), Vec3(0.1, 0.0, 0.0));
    EXPECT_DOUBLE_EQ(wall.penetration_m(Vec3(0.001, 0.0, 0.0)), 0.001);
    // f = (k p - b n·v) n = (20 + 0.5) (-1, 0, 0)
    expect_near(f.force_n, Vec3(-20.5, 0.0, 0.0), 1e-12, "force");
    expect_near(f.stiffness_n_per_m, Mat3(Vec3(2.0e4, 0, 0), Vec3(0.0), Vec3(0.0)), 1e-9, "K");
    expect_near(f.damping_n_s_per_m, Mat3(Vec3(5.0, 0, 0), Vec3(0.0), Vec3(0.0)), 1e-12, "B");
}

TEST(EnvWall, ZeroInFreeSpace) {
    const Wall wall = oblique_wall();
    const Vec3 n = wall.normal_in_free_space;
    for (double distance : {1e-9, 1e-4, 0.1}) {
        const Vec3 x = (wall.offset_m + distance) * n + 0.05 * glm::normalize(Vec3(2.0, -1.0, 0.0));
        const PenaltyForce f = wall.evaluate(x, -5.0 * n);  // even rushing toward it
        EXPECT_EQ(f.force_n, Vec3(0.0));
        EXPECT_EQ(f.stiffness_n_per_m, Mat3(0.0));
        EXPECT_EQ(f.damping_n_s_per_m, Mat3(0.0));
    }
}

TEST(EnvWall, PushesOnlyNeverPulls) {
    const Wall wall = oblique_wall();
    const Vec3 n = wall.normal_in_free_space;
    const Vec3 x = (wall.offset_m - 0.001) * n;  // 1 mm deep: k p = 20 N
    // Leaving at 1 m/s: k p - b n·v = 20 - 30 < 0: no pull, no Jacobian.
    const PenaltyForce leaving = wall.evaluate(x, 1.0 * n);
    EXPECT_EQ(leaving.force_n, Vec3(0.0));
    EXPECT_EQ(leaving.stiffness_n_per_m, Mat3(0.0));
    // Leaving slowly: still pushes, less than the spring alone.
    const PenaltyForce slow = wall.evaluate(x, 0.1 * n);
    EXPECT_NEAR(glm::dot(slow.force_n, n), 20.0 - 3.0, 1e-9);
    EXPECT_NEAR(glm::length(slow.force_n - glm::dot(slow.force_n, n) * n), 0.0, 1e-12);
}

TEST(EnvWall, JacobianMatchesFiniteDifferences) {
    const Wall wall = oblique_wall();
    const Vec3 n = wall.normal_in_free_space;
    const Vec3 x = (wall.offset_m - 0.002) * n + Vec3(0.01, -0.01, 0.0);
    const Vec3 v(0.03, -0.1, 0.02);
    const PenaltyForce f = wall.evaluate(x, v);
    expect_near(f.stiffness_n_per_m, fd_stiffness(wall, x, v), 1e-3, "stiffness");
    expect_near(f.damping_n_s_per_m, fd_damping(wall, x, v), 1e-5, "damping");
    expect_near(f.stiffness_n_per_m, 2.0e4 * glm::outerProduct(n, n), 1e-9, "k n nᵀ");
}

// Work done ON the tool over closed paths through the wall: never positive (passive), and
// strictly negative with damping. The velocity is the path's own derivative.
TEST(EnvWall, PassiveOverClosedPaths) {
    for (const double damping : {0.0, 5.0, 200.0}) {
        Wall wall = oblique_wall();
        wall.damping_n_s_per_m = damping;
        const Vec3 n = wall.normal_in_free_space;
        const Vec3 tangent = glm::normalize(glm::cross(n, Vec3(0.0, 0.0, 1.0)));
        const double period_s = 0.2;
        const int steps = 200000;
        const double dt = period_s / steps;
        double work_on_tool_j = 0.0;
        for (int i = 0; i < steps; ++i) {
            const double t = (i + 0.5) * dt;  // midpoint rule
            const double w = 2.0 * kPi / period_s;
            // An ellipse in the (n, tangent) plane reaching 3 mm into the wall.
            const Vec3 x = (wall.offset_m + 0.002 + 0.005 * std::cos(w * t)) * n +
                           0.004 * std::sin(w * t) * tangent;
            const Vec3 v = -0.005 * w * std::sin(w * t) * n + 0.004 * w * std::cos(w * t) * tangent;
            work_on_tool_j += glm::dot(wall.evaluate(x, v).force_n, v) * dt;
        }
        EXPECT_LE(work_on_tool_j, 1e-9) << "damping " << damping;
        if (damping > 0.0) {
            EXPECT_LT(work_on_tool_j, -1e-6) << "damping " << damping;
        } else {
            EXPECT_NEAR(work_on_tool_j, 0.0, 1e-8);  // conservative
        }
    }
}

TEST(EnvSpring, ClosedFormAndFiniteDifferences) {
    const Spring spring{Vec3(0.01, -0.02, 0.03), 150.0};
    const Vec3 x(0.02, 0.0, 0.0);
    const PenaltyForce f = spring.evaluate(x, Vec3(1.0));
    expect_near(f.force_n, Vec3(-1.5, -3.0, 4.5), 1e-12, "force");
    expect_near(f.stiffness_n_per_m, Mat3(150.0), 1e-12, "K");
    expect_near(f.damping_n_s_per_m, Mat3(0.0), 0.0, "B");
    expect_near(f.stiffness_n_per_m, fd_stiffness(spring, x, Vec3(1.0)), 1e-5, "fd K");
}

TEST(EnvDamper, ClosedFormAndFiniteDifferences) {
    const Damper damper{4.0};
    const Vec3 v(0.1, -0.2, 0.3);
    const PenaltyForce f = damper.evaluate(Vec3(0.5), v);
    expect_near(f.force_n, Vec3(-0.4, 0.8, -1.2), 1e-12, "force");
    expect_near(f.damping_n_s_per_m, Mat3(4.0), 1e-12, "B");
    expect_near(f.stiffness_n_per_m, Mat3(0.0), 0.0, "K");
    expect_near(f.damping_n_s_per_m, fd_damping(damper, Vec3(0.5), v), 1e-6, "fd B");
}

Detent oblique_detent(bool periodic) {
    return Detent{glm::normalize(Vec3(3.0, 4.0, 0.0)), Vec3(0.001, 0.0, 0.0), 0.005, 0.8, periodic};
}

TEST(EnvDetent, ClosedFormAndFiniteDifferences) {
    const Detent detent = oblique_detent(true);
    const Vec3 a = detent.axis;
    for (const double s : {0.0, 0.0007, 0.00125, 0.0031, -0.0093}) {
        const Vec3 x = detent.center_m + s * a + Vec3(0.0, 0.0, 0.02);  // off-axis: no effect
        const PenaltyForce f = detent.evaluate(x, Vec3(0.0));
        const double k = 2.0 * kPi / 0.005;
        expect_near(f.force_n, -0.8 * std::sin(k * s) * a, 1e-12, "force");
        expect_near(f.stiffness_n_per_m, 0.8 * k * std::cos(k * s) * glm::outerProduct(a, a), 1e-9,
                    "K");
        expect_near(f.stiffness_n_per_m, fd_stiffness(detent, x, Vec3(0.0), 1e-9), 2e-3, "fd K");
    }
    // Notch centres are stable equilibria with stiffness 2π F/λ; half-way they are unstable.
    EXPECT_NEAR(detent.evaluate(detent.center_m, Vec3(0.0)).stiffness_n_per_m[0][0],
                0.8 * 2.0 * kPi / 0.005 * a.x * a.x, 1e-9);
    EXPECT_LT(detent.evaluate(detent.center_m + 0.0025 * a, Vec3(0.0)).stiffness_n_per_m[0][0],
              0.0);
}

TEST(EnvDetent, SingleNotchIsZeroOutsideOnePeriod) {
    const Detent notch = oblique_detent(false);
    const Vec3 a = notch.axis;
    EXPECT_EQ(notch.evaluate(notch.center_m + 0.0026 * a, Vec3(0.0)).force_n, Vec3(0.0));
    EXPECT_EQ(notch.evaluate(notch.center_m - 0.01 * a, Vec3(0.0)).force_n, Vec3(0.0));
    EXPECT_GT(glm::length(notch.evaluate(notch.center_m + 0.001 * a, Vec3(0.0)).force_n), 0.1);
    // Continuous at the edge: the force tends to zero there.
    EXPECT_LT(glm::length(notch.evaluate(notch.center_m + 0.0024999 * a, Vec3(0.0)).force_n),
              2e-4);  // 0.8 N · sin(2π · 0.1 µm / 5 mm) ≈ 1e-4 N
}

TEST(EnvDetent, ConservativeAroundClosedPaths) {
    for (const bool periodic : {true, false}) {
        const Detent detent = oblique_detent(periodic);
        const int steps = 100000;
        double work_j = 0.0;
        double travel_j = 0.0;  // |work| on the outbound half, to show the path matters
        for (int i = 0; i < steps; ++i) {
            const double t = (i + 0.5) / steps * 2.0 * kPi;
            const Vec3 x(0.006 * std::cos(t), 0.009 * std::sin(t), 0.0);
            const Vec3 dx =
                Vec3(-0.006 * std::sin(t), 0.009 * std::cos(t), 0.0) * (2.0 * kPi / steps);
            const double dw = glm::dot(detent.evaluate(x, Vec3(0.0)).force_n, dx);
            work_j += dw;
            if (i < steps / 2) travel_j += std::abs(dw);
        }
        EXPECT_GT(travel_j, 1e-3);
        EXPECT_NEAR(work_j, 0.0, 1e-9) << (periodic ? "periodic" : "single notch");
    }
}

StickSlipFriction friction_3000() {
    StickSlipFriction f;
    f.normal_force_n = 2.0;
    f.static_coefficient = 0.5;   // F_s = 1 N
    f.kinetic_coefficient = 0.3;  // F_k = 0.6 N
    f.stiffness_n_per_m = 3000.0;
    f.reset(Vec3(0.0));
    return f;
}

TEST(EnvFriction, SticksBelowTheStaticLimit) {
    const StickSlipFriction friction = friction_3000();
    const Vec3 x(0.0003, 0.0, 0.0);  // 0.9 N < F_s
    const PenaltyForce f = friction.evaluate(x, Vec3(0.0));
    expect_near(f.force_n, Vec3(-0.9, 0.0, 0.0), 1e-12, "force");
    expect_near(f.stiffness_n_per_m, Mat3(3000.0), 1e-9, "K");
    expect_near(f.stiffness_n_per_m, fd_stiffness(friction, x, Vec3(0.0)), 1e-3, "fd K");
}

TEST(EnvFriction, BreaksAwayAtTheStaticLimitAndSlidesAtTheKineticOne) {
    StickSlipFriction friction = friction_3000();
    const Vec3 direction = glm::normalize(Vec3(1.0, 1.0, 0.0));
    // Pull slowly along `direction`: the force grows to F_s, then drops to F_k.
    double peak_n = 0.0;
    bool slipped = false;
    for (int i = 1; i <= 400; ++i) {
        const Vec3 x = (i * 1e-5) * direction;
        const PenaltyForce f = friction.evaluate(x, Vec3(0.0));
        const double magnitude = glm::length(f.force_n);
        peak_n = std::max(peak_n, magnitude);
        EXPECT_LE(magnitude, 1.0 + 1e-12);
        EXPECT_NEAR(glm::dot(f.force_n, direction), -magnitude, 1e-12);  // opposes the pull
        friction.commit(x, Vec3(0.0));
        if (friction.slipping) {
            slipped = true;
            EXPECT_NEAR(magnitude, 0.6, 1e-12);
        }
    }
    EXPECT_TRUE(slipped);
    EXPECT_NEAR(peak_n, 1.0, 3000.0 * 1e-5);  // within one step of the stiction spring
    // Sliding: the anchor trails the tool by F_k / k_f.
    const Vec3 tool = 400e-5 * direction;
    EXPECT_NEAR(glm::length(tool - friction.anchor_m), 0.6 / 3000.0, 1e-12);
    // The tool stops: it sticks again, and now holds up to F_s before slipping.
    friction.commit(tool, Vec3(0.0));
    EXPECT_FALSE(friction.slipping);
    const Vec3 pulled = tool + (0.3 / 3000.0) * direction;  // 0.9 N
    EXPECT_NEAR(glm::length(friction.evaluate(pulled, Vec3(0.0)).force_n), 0.9, 1e-9);
}

TEST(EnvFriction, SlipJacobianMatchesFiniteDifferences) {
    StickSlipFriction friction = friction_3000();
    friction.slipping = true;
    const Vec3 x(0.0004, 0.0002, -0.0001);  // |k z| > F_k
    const PenaltyForce f = friction.evaluate(x, Vec3(0.0));
    EXPECT_NEAR(glm::length(f.force_n), 0.6, 1e-12);
    expect_near(f.stiffness_n_per_m, fd_stiffness(friction, x, Vec3(0.0), 1e-9), 1e-3, "fd K");
}

TEST(EnvFriction, DissipatesOverClosedPaths) {
    StickSlipFriction friction = friction_3000();
    double work_on_tool_j = 0.0;
    Vec3 previous(0.0);
    const int steps = 20000;
    for (int cycle = 0; cycle < 3; ++cycle) {
        for (int i = 1; i <= steps; ++i) {
            const double t = 2.0 * kPi * i / steps;
            const Vec3 x(0.002 * std::sin(t), 0.001 * (1.0 - std::cos(t)), 0.0);
            const PenaltyForce f = friction.evaluate(x, Vec3(0.0));
            work_on_tool_j += glm::dot(f.force_n, x - previous);
            friction.commit(x, Vec3(0.0));
            previous = x;
        }
    }
    // Stored energy at the end is at most F_s²/(2 k); everything else was dissipated.
    EXPECT_LT(work_on_tool_j, -0.5 * 0.6 * 0.002 * 4.0 * 3.0);  // about F_k·path
    friction.reset(Vec3(0.0));
    EXPECT_EQ(friction.anchor_m, Vec3(0.0));
    EXPECT_FALSE(friction.slipping);
}

}  // namespace
}  // namespace hapticd::env
