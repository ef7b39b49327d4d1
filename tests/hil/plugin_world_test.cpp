// HilPluginWorld: a lab's own world through the environment plugin ABI (env/plugin_abi.h) in
// the unchanged hapticd, in lockstep against the sim. The example's spring wall renders, force
// for force, what hapticd's own [[wall]] renders in its place; a world that errs, gives a NaN,
// throws or takes too long ends the run at zero force with fault `environment` and its reason,
// and never crashes the daemon.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "tuned_gains.hpp"

namespace hapticd::testing {
namespace {

// The hand pushes the handle 10 mm down into a wall 5 mm below where it starts.
DaemonConfig pushing_config() {
    DaemonConfig config;
    config.coupling = coupling_table(size_coupling("passive"), "passive");
    config.humans = human_table(stiff_grasp(push_toml(-0.01, 0.2, 0.3, 1.0)));
    return config;
}

constexpr const char* kHead = "[scene]\nname = \"mine\"\naxes = 1\n";

class HilPluginWorld : public ::testing::Test {
  protected:
    void SetUp() override { ::setenv("HAPTICD_PLUGIN_PATH", HAPTICD_TEST_ENV_PLUGIN_DIR, 1); }
    void TearDown() override { ::unsetenv("HAPTICD_PLUGIN_PATH"); }
};

TEST_F(HilPluginWorld, TheSpringWallPluginRendersForceForForceWhatTheBuiltInWallRenders) {
    const ScratchDir own_dir;
    const ScratchDir plugin_dir;
    const DaemonConfig config = pushing_config();
    const DaemonRun own = run_hapticd(
        own_dir, {.config_toml = config.toml(),
                  .scene_toml = std::string(kHead) +
                                "[[wall]]\nnormal = [1.0]\noffset = -0.005\nstiffness = 1e5\n"
                                "damping = 2.0\n",
                  .duration_s = 1.5});
    const DaemonRun plugin = run_hapticd(
        plugin_dir,
        {.config_toml = config.toml(),
         .scene_toml = std::string(kHead) + "[plugin]\nname = \"spring-wall\"\n[plugin.settings]\n"
                                            "stiffness = 1e5\ndamping = 2.0\nposition = -0.005\n",
         .duration_s = 1.5});
    ASSERT_EQ(own.exit_code, 0) << own.err;
    ASSERT_EQ(plugin.exit_code, 0) << plugin.err;
    EXPECT_EQ(fault_list(plugin), "");
    ASSERT_EQ(plugin.log.rows(), own.log.rows());
    ASSERT_EQ(plugin.log.rows(), 1500u);
    double peak_force_n = 0.0;
    for (const char* column : {"x0_m", "v0_mps", "xe0_m", "f0_n", "energy_j"}) {
        const auto& a = own.log.column(column);
        const auto& b = plugin.log.column(column);
        for (std::size_t i = 0; i < a.size(); ++i) {
            ASSERT_EQ(a[i], b[i]) << column << " row " << i;
        }
    }
    for (const double f : plugin.log.column("f0_n"))
        peak_force_n = std::max(peak_force_n, std::abs(f));
    EXPECT_GT(peak_force_n, 1.0);  // the hand did push into the wall
    EXPECT_NE(plugin.err.find("scene mine"), std::string::npos) << plugin.err;
}

struct Misbehaviour {
    const char* mode;
    const char* says;
};

TEST_F(HilPluginWorld, AWorldThatMisbehavesEndsTheRunAtZeroForceWithItsReason) {
    for (const Misbehaviour m : {Misbehaviour{"error", "evaluate() returned 7"},
                                 Misbehaviour{"nan", "evaluate() gave a value that is not finite"},
                                 Misbehaviour{"throw", "threw: the test world's own exception"},
                                 Misbehaviour{"slow", "over its max_call_us 500"}}) {
        SCOPED_TRACE(m.mode);
        const ScratchDir dir;
        const DaemonRun run =
            run_hapticd(dir, {.config_toml = pushing_config().toml(),
                              .scene_toml = std::string(kHead) +
                                            "[plugin]\nname = \"misbehaving\"\nmax_call_us = 500\n"
                                            "[plugin.settings]\nmode = \"" +
                                            m.mode + "\"\nafter = 300\n",
                              .duration_s = 1.0});
        EXPECT_EQ(run.exit_code, 1) << run.err;
        EXPECT_EQ(fault_list(run), "environment");
        ASSERT_TRUE(run.summary.contains("environment_failure")) << run.summary.dump();
        EXPECT_NE(run.summary.at("environment_failure").get<std::string>().find(m.says),
                  std::string::npos)
            << run.summary.at("environment_failure");
        EXPECT_EQ(run.summary.at("final_command"), "zero");
        EXPECT_NE(run.err.find("hapticd: the environment failed: "), std::string::npos) << run.err;
        // From the tick that latched it, the fault is in every record and the force is zero.
        const auto& faults = run.log.column("faults");
        const auto& force = run.log.column("f0_n");
        std::size_t first = faults.size();
        for (std::size_t i = 0; i < faults.size(); ++i) {
            if ((static_cast<std::uint32_t>(faults[i]) & (1u << 9)) != 0u) {
                first = std::min(first, i);
                EXPECT_EQ(force[i], 0.0) << "row " << i;
            } else {
                EXPECT_EQ(first, faults.size()) << "the fault cleared at row " << i;
            }
        }
        ASSERT_LT(first, faults.size());
        EXPECT_GE(first, 300u);  // not before the world misbehaved
    }
}

}  // namespace
}  // namespace hapticd::testing
