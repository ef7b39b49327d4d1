// PenaltyScene: sums its objects exactly, masks the unused axes, carries friction state
// through commit/reset, and never allocates in the tick.
#include "hapticd/env/penalty_scene.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <random>

#include "alloc_guard.hpp"
#include "test_helpers.hpp"

namespace hapticd::env {
namespace {

using testing::expect_near;

PenaltyObjects mixed_objects() {
    PenaltyObjects objects;
    objects.walls.push_back(Wall{glm::normalize(Vec3(0.0, 0.0, 1.0)), -0.01, 1e4, 10.0});
    objects.walls.push_back(Wall{glm::normalize(Vec3(-1.0, 1.0, 0.0)), -0.02, 5e3, 0.0});
    objects.springs.push_back(Spring{Vec3(0.01, 0.0, -0.01), 100.0});
    objects.dampers.push_back(Damper{2.0});
    objects.detents.push_back(Detent{Vec3(0.0, 1.0, 0.0), Vec3(0.0), 0.004, 0.5, true});
    StickSlipFriction friction;
    friction.normal_force_n = 1.0;
    friction.static_coefficient = 0.8;
    friction.kinetic_coefficient = 0.5;
    friction.stiffness_n_per_m = 2000.0;
    objects.frictions.push_back(friction);
    return objects;
}

TEST(EnvPenaltyScene, SumsItsObjects) {
    const PenaltyObjects objects = mixed_objects();
    const PenaltyScene scene(objects, 3);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> position(-0.03, 0.03);
    std::uniform_real_distribution<double> velocity(-0.2, 0.2);
    for (int trial = 0; trial < 200; ++trial) {
        const Vec3 x(position(rng), position(rng), position(rng));
        const Vec3 v(velocity(rng), velocity(rng), velocity(rng));
        PenaltyForce expected;
        auto add = [&](const PenaltyForce& f) {
            expected.force_n += f.force_n;
            expected.stiffness_n_per_m += f.stiffness_n_per_m;
            expected.damping_n_s_per_m += f.damping_n_s_per_m;
        };
        for (const auto& o : objects.walls) add(o.evaluate(x, v));
        for (const auto& o : objects.springs) add(o.evaluate(x, v));
        for (const auto& o : objects.dampers) add(o.evaluate(x, v));
        for (const auto& o : objects.detents) add(o.evaluate(x, v));
        for (const auto& o : objects.frictions) add(o.evaluate(x, v));
        const PenaltyForce actual = scene.evaluate(x, v);
        expect_near(actual.force_n, expected.force_n, 1e-12, "force");
        expect_near(actual.stiffness_n_per_m, expected.stiffness_n_per_m, 1e-9, "K");
        expect_near(actual.damping_n_s_per_m, expected.damping_n_s_per_m, 1e-12, "B");
    }
}

TEST(EnvPenaltyScene, OneAxisWallHasNothingBeyondX) {
    PenaltyObjects objects;
    objects.walls.push_back(Wall{Vec3(-1.0, 0.0, 0.0), 0.0, 2e4, 5.0});
    objects.springs.push_back(Spring{Vec3(0.0), 10.0});  // isotropic: would fill y and z
    const PenaltyScene scene(std::move(objects), 1);
    const PenaltyForce f = scene.evaluate(Vec3(0.001, 0.0, 0.0), Vec3(0.0));
    EXPECT_NEAR(f.force_n.x, -20.0 - 0.01, 1e-12);
    EXPECT_EQ(f.force_n.y, 0.0);
    EXPECT_EQ(f.force_n.z, 0.0);
    EXPECT_NEAR(f.stiffness_n_per_m[0][0], 2e4 + 10.0, 1e-9);
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
            if (c == 0 && r == 0) continue;
            EXPECT_EQ(f.stiffness_n_per_m[c][r], 0.0) << r << "," << c;
            EXPECT_EQ(f.damping_n_s_per_m[c][r], 0.0) << r << "," << c;
        }
    }
}

TEST(EnvPenaltyScene, CommitAndResetCarryFrictionState) {
    PenaltyScene scene(mixed_objects(), 3);
    scene.reset(Vec3(0.0));
    const Vec3 far(0.005, 0.0, 0.0);  // 10 N on the stiction spring: beyond F_s = 0.8 N
    scene.commit(far, Vec3(0.0));
    const StickSlipFriction& friction = scene.objects().frictions.front();
    EXPECT_TRUE(friction.slipping);
    EXPECT_NEAR(glm::length(far - friction.anchor_m), 0.5 / 2000.0, 1e-12);
    scene.reset(far);
    EXPECT_FALSE(scene.objects().frictions.front().slipping);
    EXPECT_EQ(scene.objects().frictions.front().anchor_m, far);
}

TEST(EnvPenaltyScene, TickNeverAllocates) {
    PenaltyScene scene(mixed_objects(), 3);
    ImpedanceEnvironment& environment = scene;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> position(-0.03, 0.03);
    double checksum = 0.0;
    const hapticd::testing::AllocationGuard guard;
    for (int tick = 0; tick < 10000; ++tick) {
        const Vec3 x(position(rng), position(rng), position(rng));
        for (int solve = 0; solve < 3; ++solve) {
            checksum += environment.evaluate(x, Vec3(0.01 * solve)).force_n.x;
        }
        environment.commit(x, Vec3(0.0));
        if (tick % 1000 == 0) environment.reset(x);
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_TRUE(std::isfinite(checksum));
}

}  // namespace
}  // namespace hapticd::env
