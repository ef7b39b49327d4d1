// The start-up check's assumptions: [operator] classes and [coupling] environments = "scene"
// (daemon/startup_check.hpp), each stated in the verdict.
#include "hapticd/daemon/startup_check.hpp"

#include <gtest/gtest.h>

#include <string>

namespace hapticd::daemon {
namespace {

const std::string kPenOneDelayedPeriod =
    "[device.model]\nmass = 0.1\ndamping = 2\ndelay = 0.001\n"
    "[coupling]\nstiffness = 1200\ndamping = 0\n";

std::string scene_error(const std::string& scene_text) {
    try {
        (void)scene_environments(env::parse_scene(scene_text, "lab-scene.toml", 1),
                                 "lab-scene.toml");
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "no error";
}

TEST(StartupCheck, ASceneOfWallsIsItsLinearisedObjects) {
    const tune::EnvironmentAssumption walls = scene_environments(
        env::parse_scene("[scene]\nname = \"w\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\n"
                         "stiffness = 2e4\ndamping = 5\n[[spring]]\nstiffness = 100\n",
                         "w.toml", 1),
        "w.toml");
    ASSERT_EQ(walls.scene.size(), 3u);  // each, and both at once
    EXPECT_EQ(walls.scene[0].source, "[[wall]] #1");
    EXPECT_EQ(walls.scene[0].model.kind, tune::EnvironmentModel::Kind::mass_spring);
    EXPECT_EQ(walls.scene[0].model.mass_kg, 0.0);
    EXPECT_EQ(walls.scene[0].model.stiffness_n_per_m, 2e4);
    EXPECT_EQ(walls.scene[0].model.damping_n_s_per_m, 5.0);
    EXPECT_EQ(walls.scene[2].source, "all 2 objects at once");
    EXPECT_EQ(walls.scene[2].model.stiffness_n_per_m, 2e4 + 100.0);
    const tune::EnvironmentAssumption bowl = scene_environments(
        env::parse_scene("[scene]\nname = \"vm\"\naxes = 1\n[virtual_mass]\nmass = 0.5\n"
                         "stiffness = 20\n[[virtual_mass.plane]]\nnormal = [1.0]\noffset = -0.1\n",
                         "vm.toml", 1),
        "vm.toml");
    ASSERT_EQ(bowl.scene.size(), 2u);
    EXPECT_EQ(bowl.scene[0].model.mass_kg, 0.5);
    EXPECT_EQ(bowl.scene[1].model.kind, tune::EnvironmentModel::Kind::rigid_wall);
}

TEST(StartupCheck, AScenesDetentOrEmptinessIsRefusedByName) {
    EXPECT_NE(scene_error("[scene]\nname = \"d\"\naxes = 1\n[[detent]]\naxis = [1.0]\n"
                          "period = 0.01\npeak_force = 1\n")
                  .find("lab-scene.toml (scene \"d\") cannot be checked against its own objects: "
                        "[[detent]] #1"),
              std::string::npos);
    EXPECT_NE(scene_error("[scene]\nname = \"e\"\naxes = 1\n").find("has no objects"),
              std::string::npos);
}

TEST(StartupCheck, TheSceneBuysStiffnessWithADelayAndTheVerdictSaysSo) {
    // One period of delay: 1000 N/m over every passive environment, 1333 N/m against the
    // embedded demo wall (a stiff wall is nearly rigid). 1200 N/m fails the first and passes
    // the second.
    const StartupCheck every =
        check_coupling_at_startup(parse_config(kPenOneDelayedPeriod, "lab.toml", ""));
    EXPECT_FALSE(every.passed);
    EXPECT_EQ(every.holds_for, "every passive operator and every passive environment");
    Config scene =
        parse_config(kPenOneDelayedPeriod + "environments = \"scene\"\n", "lab.toml", "");
    const StartupCheck demo = check_coupling_at_startup(scene);
    EXPECT_TRUE(demo.passed) << demo.describe();
    EXPECT_NE(demo.describe().find("holds for every passive operator and the scene <embedded "
                                   "demo-wall scene>'s 1 environment: [[wall]] #1"),
              std::string::npos)
        << demo.describe();
}

// A scene loaded over the control socket is checked as built: the config's [scene] file (here
// the embedded demo wall) is not read. At 1600 N/m a soft wall passes and the demo wall fails.
TEST(StartupCheck, ASceneGivenIsCheckedInPlaceOfTheConfigsOwn) {
    const Config config = parse_config(
        "[device.model]\nmass = 0.1\ndamping = 2\ndelay = 0.001\n[coupling]\nstiffness = "
        "1600\ndamping = 0\nenvironments = \"scene\"\n",
        "lab.toml", "");
    EXPECT_FALSE(check_coupling_at_startup(config).passed);
    const env::Scene soft = env::parse_scene(
        "[scene]\nname = \"soft\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\nstiffness = 500\n",
        "soft.toml", 1);
    const StartupCheck check = check_coupling_at_startup(config, soft, "soft.toml");
    EXPECT_TRUE(check.passed) << check.describe();
    EXPECT_NE(check.describe().find("the scene soft.toml's 1 environment: [[wall]] #1"),
              std::string::npos)
        << check.describe();
    // Against every passive environment the scene is not consulted: the same verdict.
    Config every = config;
    every.coupling.environments = EnvironmentClass::every_passive;
    EXPECT_EQ(check_coupling_at_startup(every, soft, "soft.toml").describe(),
              check_coupling_at_startup(every).describe());
}

TEST(StartupCheck, AClassVerdictNamesTheClass) {
    const StartupCheck check = check_coupling_at_startup(parse_config(
        "[device.model]\nmass = 0.1\ndamping = 2\n[coupling]\nstiffness = 4000\ndamping = 1\n"
        "check = \"exact\"\n[operator]\nhand_mass = [0.1, 2]\ngrip_stiffness = [0, 3000]\n"
        "grip_damping = [2, 30]\narm_stiffness = [0, 1000]\narm_damping = [0, 20]\n",
        "lab.toml", ""));
    EXPECT_TRUE(check.passed) << check.describe();
    EXPECT_NE(check.describe().find("holds for the declared operator class (two-mass grasps with "
                                    "m_h 0.1..2 kg, k_s 0..3000 N/m, b_s 2..30 N s/m, k_a "
                                    "0..1000 N/m, b_a 0..20 N s/m, and hands-off) and every "
                                    "passive environment, proven by the class's port "
                                    "condition"),
              std::string::npos)
        << check.describe();
}

}  // namespace
}  // namespace hapticd::daemon

namespace hapticd::daemon {
namespace {

// Issue 27, item 3: hapticd with half a period of delay and check = "exact" armed 1750 N/m,
// above the proven passive bound (1600 N/m); it refuses it now, and arms 1580 N/m with the
// proof named.
TEST(StartupCheck, TheExactCheckArmsNothingPastThePassiveProof) {
    const std::string pen = "[device.model]\nmass = 0.1\ndamping = 2\ndelay = 0.0005\n";
    const StartupCheck past = check_coupling_at_startup(parse_config(
        pen + "[coupling]\nstiffness = 1750\ndamping = 0\ncheck = \"exact\"\n", "lab.toml", ""));
    EXPECT_FALSE(past.passed) << past.describe();
    const StartupCheck inside = check_coupling_at_startup(parse_config(
        pen + "[coupling]\nstiffness = 1580\ndamping = 0\ncheck = \"exact\"\n", "lab.toml", ""));
    EXPECT_TRUE(inside.passed) << inside.describe();
    EXPECT_NE(inside.describe().find("proven by the passive port condition"), std::string::npos)
        << inside.describe();
}

// Issue 27, item 1: hapticd with check = "exact" and this [operator] table armed 3929.69 N/m,
// where a member with modes at 500 and 1500 Hz grows by 1.000658 per tick; it refuses it now.
TEST(StartupCheck, TheClassCheckRefusesGainsTwoTunedModesBreak) {
    const StartupCheck check = check_coupling_at_startup(parse_config(
        "[device.model]\nmass = 0.1\ndamping = 2\n[coupling]\nstiffness = 3929.69\n"
        "damping = 0.5\ncheck = \"exact\"\n[operator]\nhand_mass = [0.05, 0.5]\n"
        "grip_stiffness = [1e5, 1e7]\ngrip_damping = [0, 1]\narm_stiffness = [1e5, 1e7]\n"
        "arm_damping = [0, 1]\n",
        "lab.toml", ""));
    EXPECT_FALSE(check.passed) << check.describe();
    EXPECT_NE(check.describe().find("two-mass grasp"), std::string::npos) << check.describe();
}

// A class's gains are armed only where its proof reaches: 3300 N/m is below the class's true
// limit (about 3441) and its search finds no unstable member there, but the class's port
// condition proves 3100 and no more, so hapticd refuses 3300 and says why.
TEST(StartupCheck, AClassIsArmedOnlyWhereItsProofReaches) {
    const auto check = [](const std::string& stiffness) {
        return check_coupling_at_startup(parse_config(
            "[device.model]\nmass = 0.1\ndamping = 2\n[coupling]\nstiffness = " + stiffness +
                "\ndamping = 0.5\ncheck = \"exact\"\n[operator]\nhand_mass = [0.05, 0.5]\n"
                "grip_stiffness = [1e5, 1e7]\ngrip_damping = [0, 1]\narm_stiffness = [1e5, 1e7]\n"
                "arm_damping = [0, 1]\n",
            "lab.toml", ""));
    };
    const StartupCheck proven = check("3100");
    EXPECT_TRUE(proven.passed) << proven.describe();
    EXPECT_NE(proven.describe().find("proven by the class's port condition"), std::string::npos)
        << proven.describe();
    const StartupCheck searched = check("3300");
    EXPECT_FALSE(searched.passed) << searched.describe();
    EXPECT_FALSE(searched.proven);
    EXPECT_NE(searched.describe().find("no proof covers it"), std::string::npos)
        << searched.describe();
    EXPECT_NE(searched.describe().find("which is no proof"), std::string::npos)
        << searched.describe();
}

}  // namespace
}  // namespace hapticd::daemon
