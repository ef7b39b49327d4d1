// Environment plugins through their C ABI (env/plugin_abi.h, plugin_environment.hpp): the
// example's spring wall renders what it says, without allocating in the tick; a world that
// errs, gives a NaN, throws or takes too long fails with its reason and is not trusted again
// until a reset; a plugin that cannot be used is refused naming the scene, the plugin and why;
// a scene's [plugin] table is read as docs/scenes.md says.
#include "hapticd/env/plugin_environment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "alloc_guard.hpp"
#include "hapticd/env/scene.hpp"

namespace hapticd::env {
namespace {

const std::string kDir = HAPTICD_TEST_ENV_PLUGIN_DIR;

std::string plugin_path(const std::string& name) {
    return kDir + "/libhapticd-env-" + name + ".so";
}

LoadedPlugin load(const std::string& name, const std::string& settings,
                  double max_call_us = 250.0) {
    return load_environment_plugin(
        PluginSpec{
            .name = plugin_path(name), .max_call_us = max_call_us, .settings_toml = settings},
        1, 1000.0, "wall.toml");
}

std::string refusal(const std::string& name, const std::string& settings) {
    try {
        (void)load_environment_plugin(
            PluginSpec{.name = name, .max_call_us = 250.0, .settings_toml = settings}, 1, 1000.0,
            "wall.toml");
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "(accepted)";
}

TEST(EnvPlugin, TheSpringWallRendersItsWallWithoutAllocatingInTheTick) {
    LoadedPlugin wall =
        load("spring-wall", "stiffness = 2000.0\ndamping = 1.5\nposition = -0.005\n");
    EXPECT_EQ(wall.name, "spring-wall");
    EXPECT_FALSE(wall.admittance);
    ASSERT_NE(wall.impedance, nullptr);
    ImpedanceEnvironment& environment = *wall.impedance;
    environment.reset(Vec3(0.0));
    const PenaltyForce free = environment.evaluate(Vec3(-0.004, 0.0, 0.0), Vec3(0.0));
    EXPECT_EQ(free.force_n, Vec3(0.0));
    const PenaltyForce inside = environment.evaluate(Vec3(-0.006, 0.0, 0.0), Vec3(-0.1, 0.0, 0.0));
    EXPECT_NEAR(inside.force_n.x, 2000.0 * 0.001 + 1.5 * 0.1, 1e-12);
    EXPECT_EQ(inside.stiffness_n_per_m[0][0], 2000.0);
    EXPECT_EQ(inside.damping_n_s_per_m[0][0], 1.5);
    EXPECT_EQ(inside.stiffness_n_per_m[1][1], 0.0);
    double checksum = 0.0;
    const hapticd::testing::AllocationGuard guard;
    for (int tick = 0; tick < 10000; ++tick) {
        const Vec3 x(-0.01 + 1e-6 * tick, 0.0, 0.0);
        for (int solve = 0; solve < 3; ++solve) {
            checksum += environment.evaluate(x, Vec3(0.01 * solve, 0.0, 0.0)).force_n.x;
        }
        environment.commit(x, Vec3(0.0));
        if (tick % 1000 == 0) environment.reset(x);
    }
    EXPECT_EQ(guard.allocations(), 0u);
    EXPECT_TRUE(std::isfinite(checksum));
    EXPECT_FALSE(environment.failed());
    EXPECT_EQ(environment.failure(), "");
}

struct Misbehaviour {
    const char* mode;
    const char* says;
};

// Each misbehaviour after 5 ticks: the first 5 are fine, then the world fails with its reason,
// gives no force, and is not called again; a reset trusts it again for 5 more.
TEST(EnvPlugin, EachMisbehaviourFailsTheWorldWithItsReasonUntilAReset) {
    for (const Misbehaviour m :
         {Misbehaviour{"error", "evaluate() returned 7"},
          Misbehaviour{"nan", "evaluate() gave a value that is not finite"},
          Misbehaviour{"throw", "evaluate() threw: the test world's own exception"},
          Misbehaviour{"slow", "over its max_call_us 1000"}}) {
        SCOPED_TRACE(m.mode);
        LoadedPlugin world =
            load("misbehaving", std::string("mode = \"") + m.mode + "\"\nafter = 5\n",
                 /*max_call_us=*/1000.0);
        ImpedanceEnvironment& environment = *world.impedance;
        for (int round = 0; round < 2; ++round) {
            environment.reset(Vec3(0.0));
            int failed_at = -1;
            for (int tick = 0; tick < 12 && failed_at < 0; ++tick) {
                (void)environment.evaluate(Vec3(0.0), Vec3(0.0));
                environment.commit(Vec3(0.0), Vec3(0.0));
                if (environment.failed()) failed_at = tick;
            }
            // "slow" fails at the second slow tick (one slow tick may be a host's stall).
            EXPECT_EQ(failed_at, std::string(m.mode) == "slow" ? 6 : 5);
            EXPECT_NE(std::string(environment.failure()).find(m.says), std::string::npos)
                << environment.failure();
            const PenaltyForce after = environment.evaluate(Vec3(-1.0, 0.0, 0.0), Vec3(0.0));
            EXPECT_EQ(after.force_n, Vec3(0.0));
            EXPECT_TRUE(environment.failed());
        }
    }
}

TEST(EnvPlugin, AnAdmittanceWorldThatGivesANanFails) {
    LoadedPlugin world = load("misbehaving-admittance", "mode = \"nan\"\nafter = 3\n");
    ASSERT_TRUE(world.admittance);
    AdmittanceEnvironment& environment = *world.admittance_environment;
    environment.reset(Vec3(0.0));
    const CouplingGains gains{.stiffness_n_per_m = 1000.0, .damping_n_s_per_m = 1.0};
    for (int tick = 0; tick < 3; ++tick) {
        EXPECT_EQ(environment.step(Vec3(0.01, 0.0, 0.0), Vec3(0.0), gains, 1e-3),
                  Vec3(0.01, 0.0, 0.0));
        EXPECT_FALSE(environment.failed());
    }
    const Vec3 tool = environment.step(Vec3(0.02, 0.0, 0.0), Vec3(0.0), gains, 1e-3);
    EXPECT_TRUE(environment.failed());
    EXPECT_EQ(tool, Vec3(0.02, 0.0, 0.0));  // no stretch: no force
    EXPECT_NE(std::string(environment.failure()).find("step() gave a value that is not finite"),
              std::string::npos);
}

TEST(EnvPlugin, APluginThatCannotBeUsedIsRefusedNamingTheSceneThePluginAndWhy) {
    const std::string other_abi = refusal(plugin_path("other-abi"), "");
    EXPECT_NE(other_abi.find("wall.toml: [plugin] name = \""), std::string::npos) << other_abi;
    EXPECT_NE(other_abi.find("built for environment plugin ABI version 99, but this hapticd "
                             "speaks version 1"),
              std::string::npos)
        << other_abi;
    const std::string device = refusal(HAPTICD_TEST_DEVICE_PLUGIN, "");
    EXPECT_NE(device.find("does not export the entry symbol 'hapticd_environment_plugin_entry'"),
              std::string::npos)
        << device;
    ::setenv("HAPTICD_PLUGIN_PATH", kDir.c_str(), 1);
    const std::string missing = refusal("nosuch", "");
    EXPECT_NE(missing.find("env plugin 'nosuch' not found; looked for:\n  " + kDir +
                           "/libhapticd-env-nosuch.so"),
              std::string::npos)
        << missing;
    const std::string bad = refusal("spring-wall", "stiffness = -5\n");
    EXPECT_NE(bad.find("create() refused: wall.toml: [plugin.settings] stiffness = -5: allowed"),
              std::string::npos)
        << bad;
    const std::string bad_mode = refusal("misbehaving", "mode = \"dance\"\n");
    EXPECT_NE(bad_mode.find("mode = \"dance\": allowed none, error, nan, throw or slow"),
              std::string::npos)
        << bad_mode;
    ::unsetenv("HAPTICD_PLUGIN_PATH");
}

TEST(EnvPlugin, ASceneNamesItsPluginAloneAndItsTimeWithinThePeriod) {
    ::setenv("HAPTICD_PLUGIN_PATH", kDir.c_str(), 1);
    const Scene scene = parse_scene(
        "[scene]\nname = \"mine\"\naxes = 1\n[plugin]\nname = \"spring-wall\"\n"
        "[plugin.settings]\nstiffness = 3000\nposition = -0.002\n",
        "mine.toml", 1, {.rate_hz = 2000.0});
    EXPECT_EQ(scene.causality, Causality::impedance);
    ASSERT_NE(scene.impedance, nullptr);
    EXPECT_EQ(scene.plugin, "spring-wall (" + kDir + "/libhapticd-env-spring-wall.so)");
    EXPECT_NE(scene.unmodelled.find("takes it for a passive environment"), std::string::npos);
    EXPECT_NEAR(scene.impedance->evaluate(Vec3(-0.003, 0.0, 0.0), Vec3(0.0)).force_n.x, 3.0, 1e-12);
    const Scene admittance = parse_scene(
        "[scene]\nname = \"m\"\naxes = 1\n[plugin]\nname = \"misbehaving-admittance\"\n", "m.toml",
        1);
    EXPECT_EQ(admittance.causality, Causality::admittance);
    ASSERT_NE(admittance.admittance, nullptr);

    const auto refused = [](const std::string& text) {
        try {
            (void)parse_scene(text, "x.toml", 1, {.rate_hz = 1000.0});
        } catch (const SceneError& e) {
            return std::string(e.what());
        }
        return std::string("(accepted)");
    };
    const std::string head = "[scene]\nname = \"x\"\naxes = 1\n";
    EXPECT_NE(refused(head + "[plugin]\nname = \"spring-wall\"\n[[wall]]\nstiffness = 1\n")
                  .find("x.toml: [plugin] is the whole scene, but this one also has [[wall]]"),
              std::string::npos);
    EXPECT_NE(refused(head + "[plugin]\nname = \"spring-wall\"\nmax_call_us = 2000\n")
                  .find("max_call_us = 2000 is out of range: allowed > 0 and <= 1000 (us)"),
              std::string::npos)
        << refused(head + "[plugin]\nname = \"spring-wall\"\nmax_call_us = 2000\n");
    EXPECT_NE(refused(head + "[plugin]\nname = \"spring-wall\"\ncolour = 1\n").find("colour"),
              std::string::npos);
    EXPECT_NE(refused(head + "[plugin]\nmax_call_us = 10\n").find("name"), std::string::npos);
    ::unsetenv("HAPTICD_PLUGIN_PATH");
}

}  // namespace
}  // namespace hapticd::env
