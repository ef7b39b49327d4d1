// The scene loader: every shipped scene builds the environment it should and nothing else;
// every bad input is rejected with the file, line, table, key, value and allowed range.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hapticd/env/god_object.hpp"
#include "hapticd/env/penalty_scene.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/env/virtual_mass.hpp"

namespace hapticd::env {
namespace {

const std::string kScenes = std::string(HAPTICD_SOURCE_DIR) + "/config/scenes/";

TEST(EnvSceneLoader, DemoWallIsOnePenaltyWallOnOneAxis) {
    const Scene scene = load_scene(kScenes + "demo-wall.toml", 1);
    EXPECT_EQ(scene.name, "demo-wall");
    EXPECT_EQ(scene.axes, 1);
    EXPECT_EQ(scene.causality, Causality::impedance);
    ASSERT_NE(scene.impedance, nullptr);
    EXPECT_EQ(scene.admittance, nullptr);
    const auto* penalty = dynamic_cast<const PenaltyScene*>(scene.impedance.get());
    ASSERT_NE(penalty, nullptr);
    EXPECT_EQ(penalty->axes(), 1);
    EXPECT_EQ(penalty->objects().size(), 1u);
    ASSERT_EQ(penalty->objects().walls.size(), 1u);
    const Wall& wall = penalty->objects().walls.front();
    EXPECT_EQ(wall.normal_in_free_space, Vec3(-1.0, 0.0, 0.0));
    EXPECT_EQ(wall.stiffness_n_per_m, 2.0e4);
    // Free at x < 0; 1 mm into the wall at x > 0 pushes back with k p = 20 N.
    EXPECT_EQ(scene.impedance->evaluate(Vec3(-0.01, 0.0, 0.0), Vec3(0.0)).force_n, Vec3(0.0));
    EXPECT_NEAR(scene.impedance->evaluate(Vec3(0.001, 0.0, 0.0), Vec3(0.0)).force_n.x, -20.0,
                1e-12);
}

TEST(EnvSceneLoader, OneAxisSceneRunsOnAThreeAxisDevice) {
    const Scene scene = load_scene(kScenes + "demo-wall.toml", 3);
    EXPECT_EQ(scene.axes, 1);
    EXPECT_EQ(scene.impedance->evaluate(Vec3(0.001, 0.5, 0.5), Vec3(0.0, 1.0, 1.0)).force_n.y, 0.0);
}

TEST(EnvSceneLoader, ShippedConstraintScenesBuildTheirEnvironments) {
    const Scene sphere = load_scene(kScenes + "god-object-sphere.toml", 3);
    EXPECT_EQ(sphere.causality, Causality::admittance);
    EXPECT_EQ(sphere.impedance, nullptr);
    const auto* god = dynamic_cast<const GodObject*>(sphere.admittance.get());
    ASSERT_NE(god, nullptr);
    EXPECT_EQ(god->constraints().planes.size(), 1u);
    ASSERT_EQ(god->constraints().spheres.size(), 1u);
    EXPECT_EQ(god->constraints().spheres.front().side, SphereSide::outside);

    const Scene box = load_scene(kScenes + "box-16-planes.toml", 3);
    const auto* box_god = dynamic_cast<const GodObject*>(box.admittance.get());
    ASSERT_NE(box_god, nullptr);
    EXPECT_EQ(box_god->constraints().planes.size(), 16u);
    EXPECT_TRUE(box_god->constraints().is_free(Vec3(0.0)));

    const Scene mass = load_scene(kScenes + "virtual-mass.toml", 3);
    const auto* virtual_mass = dynamic_cast<const VirtualMass*>(mass.admittance.get());
    ASSERT_NE(virtual_mass, nullptr);
    EXPECT_EQ(virtual_mass->parameters().mass_kg, 0.5);
    EXPECT_EQ(virtual_mass->constraints().size(), 2u);

    const Scene knob = load_scene(kScenes + "detent-friction.toml", 2);
    const auto* penalty = dynamic_cast<const PenaltyScene*>(knob.impedance.get());
    ASSERT_NE(penalty, nullptr);
    EXPECT_EQ(penalty->objects().detents.size(), 1u);
    EXPECT_EQ(penalty->objects().frictions.size(), 1u);
    EXPECT_EQ(penalty->objects().dampers.size(), 1u);
}

TEST(EnvSceneLoader, DefaultsAndNormalisation) {
    const Scene scene = parse_scene(R"(
[scene]
name = "n"
axes = 2
[[wall]]
normal = [3, 4]
stiffness = 1000
)",
                                    "mem.toml", 2);
    const auto& wall = dynamic_cast<const PenaltyScene&>(*scene.impedance).objects().walls.at(0);
    EXPECT_NEAR(wall.normal_in_free_space.x, 0.6, 1e-15);
    EXPECT_NEAR(wall.normal_in_free_space.y, 0.8, 1e-15);
    EXPECT_EQ(wall.normal_in_free_space.z, 0.0);
    EXPECT_EQ(wall.offset_m, 0.0);
    EXPECT_EQ(wall.damping_n_s_per_m, 0.0);
}

TEST(EnvSceneLoader, EmptySceneIsFreeSpace) {
    const Scene scene = parse_scene("[scene]\nname = \"free\"\naxes = 3\n", "free.toml", 3);
    EXPECT_EQ(scene.causality, Causality::impedance);
    EXPECT_EQ(scene.impedance->evaluate(Vec3(1.0), Vec3(1.0)).force_n, Vec3(0.0));
}

struct BadScene {
    std::string what;
    std::string text;
    int device_axes;
    std::vector<std::string> expected;  // all must appear in the message
};

const char* const kHeader1 = "[scene]\nname = \"s\"\naxes = 1\n";
const char* const kHeader3 = "[scene]\nname = \"s\"\naxes = 3\n";

std::vector<BadScene> bad_scenes() {
    const std::string h1 = kHeader1;
    const std::string h3 = kHeader3;
    const std::string wall = "[[wall]]\nnormal = [-1]\nstiffness = 100\n";
    return {
        {"negative stiffness in the second wall",
         h1 + wall + "[[wall]]\nnormal = [1]\noffset = -0.1\nstiffness = -5\n",
         1,
         {"x.toml:10:",
          "[[wall]] #2 stiffness = -5 is out of range: allowed > 0 and <= 1e+07 (N/m)"}},
        {"missing stiffness",
         h1 + "[[wall]]\nnormal = [-1]\n",
         1,
         {"x.toml:", "[[wall]] #1 stiffness is missing", "allowed > 0"}},
        {"stiffness not a number",
         h1 + "[[wall]]\nnormal = [-1]\nstiffness = \"hard\"\n",
         1,
         {"x.toml:6:", "[[wall]] #1 stiffness = \"hard\" is not a number"}},
        {"unknown key in a wall",
         h1 + wall + "stifness = 3\n",
         1,
         {"x.toml:7:", "[[wall]] #1 stifness = 3 is not a known key: allowed",
          "normal, offset, stiffness, damping"}},
        {"unknown top-level table",
         h1 + "[[walls]]\nnormal = [-1]\n",
         1,
         {"x.toml:4:", "[[walls]] is not a known table: allowed", "[[wall]]"}},
        {"unknown key in [scene]",
         "[scene]\nname = \"s\"\naxes = 1\nrate = 3\n",
         1,
         {"x.toml:4:", "[scene] rate = 3 is not a known key: allowed", "name, axes"}},
        {"missing [scene]", wall, 1, {"x.toml:", "[scene] is missing"}},
        {"missing axes", "[scene]\nname = \"s\"\n", 1, {"[scene] axes is missing", "allowed 1..1"}},
        {"too many axes for the device",
         h3,
         1,
         {"x.toml:3:", "[scene] axes = 3 is out of range: allowed 1..1", "1 axis"}},
        {"fractional axes",
         "[scene]\nname = \"s\"\naxes = 1.5\n",
         3,
         {"[scene] axes = 1.5 is not an integer"}},
        {"empty name", "[scene]\nname = \"\"\naxes = 1\n", 1, {"[scene] name = \"\" is empty"}},
        {"vector of the wrong length",
         h1 + "[[wall]]\nnormal = [-1, 0]\nstiffness = 1\n",
         1,
         {"x.toml:5:", "[[wall]] #1 normal = [-1, 0] has 2 components: allowed exactly 1"}},
        {"zero normal",
         h1 + "[[wall]]\nnormal = [0.0]\nstiffness = 1\n",
         1,
         {"[[wall]] #1 normal = [0.0] is out of range: allowed a non-zero direction"}},
        {"coordinate out of range",
         h3 + "[[spring]]\nanchor = [0, 0, 1000]\nstiffness = 1\n",
         3,
         {"[[spring]] #1 anchor = [0, 0, 1000] is out of range", "-100 to 100 m"}},
        {"kinetic above static friction",
         h1 + "[[friction]]\nnormal_force = 1\nstatic_coefficient = 0.5\n"
              "kinetic_coefficient = 0.7\nstiffness = 1000\n",
         1,
         {"x.toml:7:", "[[friction]] #1 kinetic_coefficient = 0.7 is out of range",
          "<= 0.5 (at most static_coefficient)"}},
        {"negative damper",
         h1 + "[[damper]]\ndamping = -1\n",
         1,
         {"[[damper]] #1 damping = -1 is out of range: allowed > 0"}},
        {"detent period zero",
         h1 + "[[detent]]\naxis = [1]\nperiod = 0\npeak_force = 1\n",
         1,
         {"[[detent]] #1 period = 0 is out of range: allowed > 0", "m"}},
        {"detent periodic not a bool",
         h1 + "[[detent]]\naxis = [1]\nperiod = 1\npeak_force = 1\nperiodic = 1\n",
         1,
         {"[[detent]] #1 periodic = 1 is not a boolean"}},
        {"wall written as a table",
         h1 + "[wall]\nnormal = [-1]\nstiffness = 1\n",
         1,
         {"wall = {...} is not an array of tables", "[[wall]]"}},
        {"mixed causality",
         h3 + "[[wall]]\nnormal = [0, 0, 1]\nstiffness = 1\n"
              "[[proxy_plane]]\nnormal = [0, 0, 1]\n",
         3,
         {"x.toml:", "one causality", "[[wall]]", "[[proxy_plane]]", "separate scenes"}},
        {"mixed causality with a virtual mass",
         h3 + "[[spring]]\nstiffness = 1\n[virtual_mass]\nmass = 1\n",
         3,
         {"one causality", "[[spring]]", "[virtual_mass]"}},
        {"god-object and virtual mass",
         h3 + "[[proxy_sphere]]\nradius = 0.1\n[virtual_mass]\nmass = 1\n",
         3,
         {"one admittance environment"}},
        {"bad sphere side",
         h3 + "[[proxy_sphere]]\nradius = 0.1\nside = \"in\"\n",
         3,
         {"x.toml:6:", "[[proxy_sphere]] #1 side = \"in\" is not allowed",
          "\"outside\" or \"inside\""}},
        {"negative radius",
         h3 + "[[proxy_sphere]]\nradius = -0.1\n",
         3,
         {"[[proxy_sphere]] #1 radius = -0.1 is out of range: allowed > 0"}},
        {"virtual mass without mass",
         h3 + "[virtual_mass]\nstiffness = 1\n",
         3,
         {"[virtual_mass] mass is missing", "kg"}},
        {"virtual mass anchor in the solid",
         h3 + "[virtual_mass]\nmass = 1\nanchor = [0, 0, -1]\n[[virtual_mass.plane]]\n"
              "normal = [0, 0, 1]\n",
         3,
         {"x.toml:6:", "[virtual_mass] anchor = [0, 0, -1] is inside a constraint"}},
        {"unknown key in a virtual-mass plane",
         h3 + "[virtual_mass]\nmass = 1\n[[virtual_mass.plane]]\nnormal = [0, 0, 1]\nd = 1\n",
         3,
         {"[[virtual_mass.plane]] #1 d = 1 is not a known key"}},
        {"no free space",
         h3 + "[[proxy_plane]]\nnormal = [0, 0, 1]\noffset = 1\n"
              "[[proxy_plane]]\nnormal = [0, 0, -1]\noffset = 1\n",
         3,
         {"no free space"}},
        {"syntax error", "[scene\nname = 1\n", 1, {"x.toml:1:", "TOML syntax error"}},
        {"device with no axes", h1, 0, {"the device has 0 axes"}},
    };
}

TEST(EnvSceneLoader, EveryBadInputIsRejectedWithWhereAndWhy) {
    for (const BadScene& bad : bad_scenes()) {
        SCOPED_TRACE(bad.what);
        try {
            (void)parse_scene(bad.text, "config/scenes/x.toml", bad.device_axes);
            ADD_FAILURE() << "accepted: " << bad.what;
        } catch (const SceneError& error) {
            const std::string message = error.what();
            for (const std::string& part : bad.expected) {
                EXPECT_NE(message.find(part), std::string::npos)
                    << "message: " << message << "\nlacks: " << part;
            }
        }
    }
}

TEST(EnvSceneLoader, MissingFileNamesThePath) {
    try {
        (void)load_scene("/nonexistent/scene.toml", 1);
        FAIL() << "accepted a missing file";
    } catch (const SceneError& error) {
        EXPECT_NE(std::string(error.what())
                      .find("/nonexistent/scene.toml: cannot read the scene file: No such file"),
                  std::string::npos)
            << error.what();
    }
}

}  // namespace
}  // namespace hapticd::env
