// The god-object: the proxy is x_d in free space, the orthogonal projection on one plane,
// the edge and corner points of two and three, slides along surfaces, does not tunnel, and
// never leaves free space over long random walks (planes, the 16-plane box, spheres).
#include "hapticd/env/god_object.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <random>

#include "alloc_guard.hpp"
#include "hapticd/env/scene.hpp"
#include "test_helpers.hpp"

namespace hapticd::env {
namespace {

using testing::expect_near;
const CouplingGains kGains{2000.0, 5.0};
constexpr double kPeriodS = 1e-3;

Vec3 step(GodObject& god, const Vec3& device_position_m) {
    return god.step(device_position_m, Vec3(0.0), kGains, kPeriodS);
}

ConstraintSet octant() {  // free where x, y, z >= 0
    ConstraintSet c;
    c.planes = {{Vec3(1, 0, 0), 0.0}, {Vec3(0, 1, 0), 0.0}, {Vec3(0, 0, 1), 0.0}};
    return c;
}

/// The nearest point of a convex polytope (planes only) by Dykstra's alternating
/// projections: slow, independent of the god-object's active-set method.
Vec3 dykstra(const std::vector<PlaneConstraint>& planes, const Vec3& goal) {
    Vec3 x = goal;
    std::vector<Vec3> increments(planes.size(), Vec3(0.0));
    for (int sweep = 0; sweep < 20000; ++sweep) {
        for (std::size_t i = 0; i < planes.size(); ++i) {
            const Vec3 y = x + increments[i];
            const Vec3 projected = gap_m(planes[i], y) < 0.0 ? project_to_surface(planes[i], y) : y;
            increments[i] = y - projected;
            x = projected;
        }
    }
    return x;
}

TEST(EnvGodObject, ProxyIsTheDeviceInFreeSpace) {
    GodObject god(octant());
    god.reset(Vec3(0.01, 0.02, 0.03));
    for (const Vec3 x : {Vec3(0.02, 0.01, 0.05), Vec3(0.1, 0.2, 0.3), Vec3(1e-6, 0.5, 1e-6)}) {
        EXPECT_EQ(step(god, x), x);
    }
}

TEST(EnvGodObject, SinglePlaneGivesTheOrthogonalProjection) {
    ConstraintSet c;
    const Vec3 n = glm::normalize(Vec3(1.0, -2.0, 2.0));
    c.planes = {{n, 0.004}};
    GodObject god(std::move(c));
    god.reset(n * 0.05);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 x_d(u(rng), u(rng), u(rng));
        const double gap = glm::dot(n, x_d) - 0.004;
        const Vec3 expected = gap >= 0.0 ? x_d : x_d - gap * n;
        expect_near(step(god, x_d), expected, 1e-12, "proxy");
    }
}

TEST(EnvGodObject, EdgesAndCorners) {
    GodObject god(octant());
    god.reset(Vec3(0.01));
    expect_near(step(god, Vec3(-0.01, -0.02, 0.03)), Vec3(0.0, 0.0, 0.03), 1e-15, "edge");
    expect_near(step(god, Vec3(-0.01, -0.02, -0.03)), Vec3(0.0), 1e-15, "corner");
    expect_near(step(god, Vec3(0.02, -0.02, -0.03)), Vec3(0.02, 0.0, 0.0), 1e-15, "release");
    expect_near(step(god, Vec3(0.02, 0.01, 0.04)), Vec3(0.02, 0.01, 0.04), 1e-15, "free");
}

TEST(EnvGodObject, SlidesAlongAPlane) {
    ConstraintSet c;
    c.planes = {{Vec3(0, 0, 1), 0.0}};
    GodObject god(std::move(c));
    god.reset(Vec3(0.0, 0.0, 0.01));
    for (int i = 0; i <= 100; ++i) {  // pressed 5 mm in, dragged 10 cm sideways
        const Vec3 x_d(0.001 * i, 0.0005 * i, -0.005);
        expect_near(step(god, x_d), Vec3(x_d.x, x_d.y, 0.0), 1e-15, "sliding proxy");
    }
}

TEST(EnvGodObject, DoesNotTunnelThroughASmallBall) {
    ConstraintSet c;
    c.spheres = {{Vec3(0.0), 0.002, SphereSide::outside}};
    GodObject god(std::move(c));
    god.reset(Vec3(-0.05, 0.0, 0.0));
    // The device jumps straight through the 4 mm ball in one tick; the proxy stays behind.
    const Vec3 proxy = step(god, Vec3(0.05, 0.0, 0.0));
    EXPECT_NEAR(proxy.x, -0.002, 1e-12);
    EXPECT_GE(gap_m(god.constraints().spheres[0], proxy), -kContactTolerance_m);
    // Slightly off-axis, the proxy works its way around the ball to the device.
    for (int tick = 0; tick < 200; ++tick) {
        const Vec3 p = step(god, Vec3(0.05, 1e-4, 0.0));
        EXPECT_GE(gap_m(god.constraints().spheres[0], p), -kContactTolerance_m);
    }
    expect_near(god.proxy_m(), Vec3(0.05, 1e-4, 0.0), 1e-12, "proxy around the ball");
}

TEST(EnvGodObject, BallProxyIsTheRadialProjection) {
    ConstraintSet c;
    c.spheres = {{Vec3(0.01, 0.0, 0.0), 0.03, SphereSide::outside}};
    GodObject god(std::move(c));
    god.reset(Vec3(0.01, 0.0, 0.05));
    const Vec3 x_d(0.02, 0.005, 0.02);  // inside, above the centre
    for (int tick = 0; tick < 20; ++tick) step(god, x_d);
    const Vec3 expected = Vec3(0.01, 0.0, 0.0) + 0.03 * glm::normalize(x_d - Vec3(0.01, 0, 0));
    expect_near(god.proxy_m(), expected, 1e-9, "radial projection");
}

// Random walks with big steps that reach well outside the box: the proxy stays inside it,
// and once the device holds still it is the nearest point of the box.
TEST(EnvGodObject, RandomWalkInTheSixteenPlaneBoxNeverLeavesIt) {
    const Scene scene =
        load_scene(std::string(HAPTICD_SOURCE_DIR) + "/config/scenes/box-16-planes.toml", 3);
    auto& god = dynamic_cast<GodObject&>(*scene.admittance);
    std::mt19937_64 rng(2024);
    std::normal_distribution<double> jitter(0.0, 0.01);
    Vec3 x_d(0.0);
    double worst_gap = 0.0;
    int holds_checked = 0;
    for (int tick = 0; tick < 200000; ++tick) {
        x_d += Vec3(jitter(rng), jitter(rng), jitter(rng));
        x_d = glm::clamp(x_d, Vec3(-0.09), Vec3(0.09));  // up to 4 cm beyond the walls
        const Vec3 proxy = step(god, x_d);
        worst_gap = std::min(worst_gap, god.constraints().min_gap_m(proxy));
        ASSERT_TRUE(god.constraints().is_free(proxy)) << "tick " << tick;
        if (tick % 5000 == 0) {
            for (int hold = 0; hold < 3; ++hold) step(god, x_d);
            expect_near(god.proxy_m(), dykstra(god.constraints().planes, x_d), 1e-9,
                        "nearest point");
            ++holds_checked;
        }
    }
    EXPECT_GE(worst_gap, -kContactTolerance_m);
    EXPECT_EQ(holds_checked, 40);
}

TEST(EnvGodObject, RandomWalkAmongSpheresAndPlanesNeverLeavesFreeSpace) {
    ConstraintSet c;
    c.planes = {{Vec3(0, 0, 1), -0.05}, {glm::normalize(Vec3(1, 1, 0)), -0.06}};
    c.spheres = {{Vec3(0.0, 0.0, -0.03), 0.025, SphereSide::outside},
                 {Vec3(0.03, 0.01, 0.0), 0.01, SphereSide::outside},
                 {Vec3(-0.02, 0.02, 0.01), 0.004, SphereSide::outside},
                 {Vec3(0.0), 0.09, SphereSide::inside}};
    GodObject god(std::move(c));
    god.reset(Vec3(0.0, 0.0, 0.04));
    ASSERT_TRUE(god.constraints().is_free(god.proxy_m()));
    std::mt19937_64 rng(99);
    std::normal_distribution<double> jitter(0.0, 0.008);
    Vec3 x_d = god.proxy_m();
    for (int tick = 0; tick < 200000; ++tick) {
        x_d =
            glm::clamp(x_d + Vec3(jitter(rng), jitter(rng), jitter(rng)), Vec3(-0.12), Vec3(0.12));
        const Vec3 proxy = step(god, x_d);
        ASSERT_GE(god.constraints().min_gap_m(proxy), -kContactTolerance_m) << "tick " << tick;
        if (god.constraints().is_free(x_d) && glm::length(x_d - proxy) > 0.0) {
            // From free space the proxy can be held back only by a surface it touches.
            EXPECT_LE(god.constraints().min_gap_m(proxy), kContactTolerance_m)
                << "tick " << tick << " iterations " << god.last_iterations();
        }
    }
}

TEST(EnvGodObject, OneAxisProxyStaysOnTheAxis) {
    ConstraintSet c;
    c.planes = {{Vec3(-1, 0, 0), 0.0}};  // demo-wall as a constraint: free at x <= 0
    GodObject god(std::move(c), 1);
    god.reset(Vec3(-0.01, 0.0, 0.0));
    expect_near(step(god, Vec3(0.01, 0.3, -0.2)), Vec3(0.0), 0.0, "on the wall");
    expect_near(step(god, Vec3(-0.02, 0.3, -0.2)), Vec3(-0.02, 0.0, 0.0), 0.0, "free");
}

TEST(EnvGodObject, StepNeverAllocates) {
    const Scene scene =
        load_scene(std::string(HAPTICD_SOURCE_DIR) + "/config/scenes/box-16-planes.toml", 3);
    AdmittanceEnvironment& environment = *scene.admittance;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-0.08, 0.08);
    double checksum = 0.0;
    const hapticd::testing::AllocationGuard guard;
    for (int tick = 0; tick < 20000; ++tick) {
        checksum += environment.step(Vec3(u(rng), u(rng), u(rng)), Vec3(0.0), kGains, kPeriodS).x;
        if (tick % 1000 == 0) environment.reset(Vec3(u(rng), u(rng), u(rng)));
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_TRUE(std::isfinite(checksum));
}

}  // namespace
}  // namespace hapticd::env
