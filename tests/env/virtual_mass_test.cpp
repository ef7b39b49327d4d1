// The constrained virtual mass: the exact implicit-Euler update of tune/exact_model.hpp,
// energy that never grows without input, passivity with input, constraints never violated.
#include "hapticd/env/virtual_mass.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <random>

#include "alloc_guard.hpp"
#include "test_helpers.hpp"

namespace hapticd::env {
namespace {

constexpr double kPeriodS = 1e-3;
const CouplingGains kGains{2000.0, 5.0};
const CouplingGains kNoInput{0.0, 0.0};

VirtualMassParameters puck() { return {0.5, 20.0, 1.0, Vec3(0.001, -0.002, 0.003)}; }

ConstraintSet bowl() {
    ConstraintSet c;
    c.planes = {{Vec3(0, 0, 1), -0.04}, {glm::normalize(Vec3(1, -1, 0)), -0.05}};
    c.spheres = {{Vec3(0.0), 0.08, SphereSide::inside},
                 {Vec3(0.03, 0.03, -0.02), 0.015, SphereSide::outside}};
    return c;
}

TEST(EnvVirtualMass, MatchesTheClosedFormImplicitEulerUpdate) {
    const VirtualMassParameters p = puck();
    VirtualMass mass(p, ConstraintSet{});
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    double x[3] = {p.anchor_m.x, p.anchor_m.y, p.anchor_m.z};
    double v[3] = {0.0, 0.0, 0.0};
    const double T = kPeriodS;
    const double D = p.mass_kg + T * (kGains.damping_n_s_per_m + p.damping_n_s_per_m) +
                     T * T * (kGains.stiffness_n_per_m + p.stiffness_n_per_m);
    for (int n = 0; n < 2000; ++n) {
        const Vec3 x_d(u(rng), u(rng), u(rng));
        const Vec3 v_d(20.0 * u(rng), 20.0 * u(rng), 20.0 * u(rng));
        const Vec3 result = mass.step(x_d, v_d, kGains, T);
        for (int i = 0; i < 3; ++i) {  // exact_model.hpp, per axis, with the anchor
            v[i] = (p.mass_kg * v[i] + T * (kGains.stiffness_n_per_m * (x_d[i] - x[i]) +
                                            kGains.damping_n_s_per_m * v_d[i] -
                                            p.stiffness_n_per_m * (x[i] - p.anchor_m[i]))) /
                   D;
            x[i] += T * v[i];
            ASSERT_NEAR(result[i], x[i], 1e-15) << "tick " << n << " axis " << i;
            ASSERT_NEAR(mass.velocity_mps()[i], v[i], 1e-13) << "tick " << n << " axis " << i;
        }
    }
    EXPECT_EQ(mass.stopped_steps(), 0);
}

// Energise the mass through the coupling, then cut the input: E never grows again.
TEST(EnvVirtualMass, EnergyNeverIncreasesWithoutInput) {
    for (const double damping : {0.0, 1.0}) {
        VirtualMassParameters p = puck();
        p.damping_n_s_per_m = damping;
        VirtualMass mass(p, bowl());
        std::mt19937_64 rng(17);
        std::uniform_real_distribution<double> u(-0.1, 0.1);
        for (int n = 0; n < 300; ++n)
            mass.step(Vec3(u(rng), u(rng), u(rng)), Vec3(0.0), kGains, kPeriodS);
        const double start_j = mass.energy_j();
        ASSERT_GT(start_j, 1e-4);
        double previous_j = start_j;
        for (int n = 0; n < 20000; ++n) {
            mass.step(Vec3(0.0), Vec3(0.0), kNoInput, kPeriodS);
            ASSERT_LE(mass.energy_j(), previous_j * (1.0 + 1e-12) + 1e-18) << "tick " << n;
            previous_j = mass.energy_j();
        }
        EXPECT_LT(mass.energy_j(), 0.5 * start_j);  // and it does go down (walls, damping)
    }
}

// With input, the stored energy grows by no more than the work the coupling force did.
TEST(EnvVirtualMass, PassiveAndAlwaysInFreeSpaceUnderRandomDrive) {
    VirtualMass mass(puck(), bowl());
    std::mt19937_64 rng(23);
    std::normal_distribution<double> jitter(0.0, 0.01);
    Vec3 x_d(0.0);
    Vec3 x_d_prev(0.0);
    double supplied_j = 0.0;
    const double start_j = mass.energy_j();
    for (int n = 0; n < 100000; ++n) {
        x_d =
            glm::clamp(x_d + Vec3(jitter(rng), jitter(rng), jitter(rng)), Vec3(-0.15), Vec3(0.15));
        const Vec3 v_d = (x_d - x_d_prev) / kPeriodS;
        const Vec3 x_prev = mass.position_m();
        const Vec3 x = mass.step(x_d, v_d, kGains, kPeriodS);
        const Vec3 force_n = kGains.stiffness_n_per_m * (x_d - x) +
                             kGains.damping_n_s_per_m * (v_d - mass.velocity_mps());
        supplied_j += glm::dot(force_n, x - x_prev);
        ASSERT_GE(mass.constraints().min_gap_m(x), -kContactTolerance_m) << "tick " << n;
        ASSERT_LE(mass.energy_j() - start_j, supplied_j + 1e-9) << "tick " << n;
        x_d_prev = x_d;
    }
    // The stop is a backstop (a solid ball's non-convex free space), not the mechanism.
    EXPECT_LT(mass.stopped_steps(), 1000) << mass.stopped_steps();
    RecordProperty("stopped_steps", static_cast<int>(mass.stopped_steps()));
}

TEST(EnvVirtualMass, StopsInelasticallyOnAPlane) {
    ConstraintSet floor;
    floor.planes = {{Vec3(0, 0, 1), 0.0}};
    VirtualMass mass({0.2, 0.0, 0.0, Vec3(0.0, 0.0, 0.01)}, floor);
    // Pull it down and sideways hard: it lands on the floor and slides, never bounces.
    for (int n = 0; n < 200; ++n) mass.step(Vec3(0.05, 0.0, -0.1), Vec3(0.0), kGains, kPeriodS);
    EXPECT_NEAR(mass.position_m().z, 0.0, 1e-15);
    EXPECT_GE(mass.velocity_mps().z, 0.0);
    EXPECT_GT(mass.position_m().x, 0.01);
    for (int n = 0; n < 2000; ++n) mass.step(Vec3(0.05, 0.0, 0.005), Vec3(0.0), kGains, kPeriodS);
    EXPECT_NEAR(mass.position_m().z, 0.005, 1e-3);  // lifts off again when let go
}

TEST(EnvVirtualMass, StepNeverAllocates) {
    VirtualMass mass(puck(), bowl());
    AdmittanceEnvironment& environment = mass;
    std::mt19937_64 rng(29);
    std::uniform_real_distribution<double> u(-0.1, 0.1);
    double checksum = 0.0;
    const hapticd::testing::AllocationGuard guard;
    for (int n = 0; n < 20000; ++n) {
        checksum +=
            environment.step(Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng)), kGains, kPeriodS).x;
        if (n % 1000 == 0) environment.reset(Vec3(u(rng), u(rng), u(rng)));
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_TRUE(std::isfinite(checksum));
}

}  // namespace
}  // namespace hapticd::env
