// haptic-tune size and check, end to end through the real executable.
#include <gtest/gtest.h>

#include <cctype>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd {
namespace {

using hapticd::testing::run_command;
using hapticd::testing::ScratchDir;
using nlohmann::json;

std::string tune(const std::string& args) { return std::string(HAPTIC_TUNE) + " " + args; }

TEST(HapticTuneSize, PrintsThePublicFieldsAsJson) {
    const auto r = tune("size --mass 0.1 --damping 2 --rate 1000 --model encoder --json");
    const auto result = run_command(r);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const json j = json::parse(result.out);
    EXPECT_NEAR(j.at("stiffness").get<double>(), 4000.0, 1e-6);  // Colgate: 2b/T
    EXPECT_EQ(j.at("damping").get<double>(), 0.0);
    EXPECT_EQ(j.at("binding_frequency_hz").get<double>(), 0.0);
    EXPECT_EQ(j.at("model"), "encoder");
    EXPECT_GT(j.at("solver_time_s").get<double>(), 0.0);
}

TEST(HapticTuneSize, ReadsTheDeviceFromAConfigFileAndFlagsOverrideIt) {
    const std::string config = std::string(HAPTICD_SOURCE_DIR) + "/config/devices/pen-display.toml";
    const auto from_file = run_command(tune("size --config " + config + " --json"));
    ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
    EXPECT_NEAR(json::parse(from_file.out).at("stiffness").get<double>(), 4000.0, 1e-6);
    const auto overridden = run_command(tune("size --config " + config + " --damping 1 --json"));
    ASSERT_EQ(overridden.exit_code, 0) << overridden.err;
    EXPECT_NEAR(json::parse(overridden.out).at("stiffness").get<double>(), 2000.0, 1e-6);
}

// The encoder model's optimised pair is stiffer, and the exact model rejects it: size says
// so and exits 1 (docs/stability-models.md, "What the tools do"). The passive model's optimum
// is no damping at 2b/T, and passes.
TEST(HapticTuneSize, AnAnswerTheExactModelRejectsExitsOne) {
    const auto result = run_command(
        tune("size --mass 0.1 --damping 2 --rate 1000 --optimize-damping --model encoder --json"));
    EXPECT_EQ(result.exit_code, 1) << result.err;
    const json j = json::parse(result.out);
    EXPECT_GT(j.at("stiffness").get<double>(), 4000.0);
    EXPECT_GT(j.at("damping").get<double>(), 0.0);
    EXPECT_GT(j.at("binding_frequency_hz").get<double>(), 0.0);
    // The encoder model ignores the hold's alias at Nyquist (docs/stability-models.md).
    EXPECT_FALSE(j.at("exact_check").at("stable").get<bool>());
    EXPECT_NE(result.err.find("the exact sampled-data model finds this design unstable"),
              std::string::npos);

    const auto passive =
        run_command(tune("size --mass 0.1 --damping 2 --rate 1000 --optimize-damping --json"));
    ASSERT_EQ(passive.exit_code, 0) << passive.err;
    const json p = json::parse(passive.out);
    EXPECT_EQ(p.at("model"), "passive");
    EXPECT_NEAR(p.at("stiffness").get<double>(), 4000.0, 1e-5);
    EXPECT_NEAR(p.at("damping").get<double>(), 0.0, 1e-6);
    EXPECT_TRUE(p.at("exact_check").at("stable").get<bool>());
}

// A delay of d periods: at b_c = 0 the passive model allows k_c = 2b/(T τ²) against every
// passive environment, τ² = (1 + d)² for whole periods, (1 + 3d) for d < 1.
TEST(HapticTuneSize, DelayLowersThePassiveBound) {
    for (auto [delay, tau2] : {std::pair{"0.001", 4.0}, {"0.0005", 2.5}, {"0.002", 9.0}}) {
        const auto r = run_command(
            tune(std::string("size --mass 0.1 --damping 2 --rate 1000 --json --delay ") + delay));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const json j = json::parse(r.out);
        EXPECT_NEAR(j.at("stiffness").get<double>(), 4000.0 / tau2, 1e-4) << delay;
        EXPECT_EQ(j.at("delay_s").get<double>(), std::stod(delay));
        EXPECT_TRUE(j.at("exact_check").at("stable").get<bool>()) << delay;
    }
}

TEST(HapticTuneSize, BadDelayAndExtremeMassesAreUsageErrorsNamingTheRange) {
    struct Bad {
        const char* args;
        const char* message;
    };
    for (const Bad bad :
         {Bad{"--delay -0.001", "--delay: value -0.001 is out of range: allowed finite and >= 0"},
          Bad{"--delay nan", "--delay: value nan is out of range"},
          Bad{"--delay 0.01", "--delay 0.01 s is out of range: allowed >= 0 and < 10 periods"},
          Bad{"--mass 1e-20 --delay 0",
              "device mass m = 1e-20 kg is out of range: allowed 0.0001 to 1000"}}) {
        std::string args = std::string(bad.args);
        if (args.find("--mass") == std::string::npos) args += " --mass 0.1";
        for (const char* command : {"size", "check --stiffness 100 --model exact"}) {
            const auto r =
                run_command(tune(std::string(command) + " --damping 2 --rate 1000 " + args));
            EXPECT_EQ(r.exit_code, 2) << command << " " << args;
            EXPECT_NE(r.err.find(bad.message), std::string::npos) << r.err;
        }
    }
    const auto huge =
        run_command(tune("check --mass 0.1 --damping 2 --rate 1000 --stiffness 100 "
                         "--coupling-damping 1e307 --model exact"));
    EXPECT_EQ(huge.exit_code, 2);
    EXPECT_NE(
        huge.err.find("coupling damping b_c = 1e+307 N s/m is out of range: allowed 0 to 100000"),
        std::string::npos)
        << huge.err;
}

TEST(HapticTuneSize, DefaultDesignPassesTheExactCrossCheckQuietly) {
    const auto result = run_command(tune("size --mass 0.1 --damping 2 --rate 1000 --json"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_TRUE(json::parse(result.out).at("exact_check").at("stable").get<bool>());
    EXPECT_EQ(result.err, "");
    const auto skipped =
        run_command(tune("size --mass 0.1 --damping 2 --rate 1000 --json --no-exact-check"));
    EXPECT_FALSE(json::parse(skipped.out).contains("exact_check"));
}

TEST(HapticTuneSize, TextOutputNamesEveryField) {
    const auto result = run_command(tune("size --mass 0.1 --damping 2 --rate 1000"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    for (const char* key :
         {"stiffness", "damping", "binding_frequency_hz", "model", "solver_time_s"}) {
        EXPECT_NE(result.out.find(key), std::string::npos) << key;
    }
}

TEST(HapticTuneSize, AdmittanceDisplayExplainsAnInfeasibleLoop) {
    const auto result = run_command(
        tune("size --display admittance --mass 2 --damping 5 --rate 1000 --kp 2000 --ki 0 "
             "--model encoder"));
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.err.find("(35) fails"), std::string::npos) << result.err;
}

struct BadInput {
    std::string args;
    std::string must_name;
};
void PrintTo(const BadInput& b, std::ostream* os) { *os << b.args; }

class HapticTuneBadInput : public ::testing::TestWithParam<BadInput> {};

// Readable, stable test names: "size_mass_-1_..." -> letters and digits only.
std::string bad_input_name(const ::testing::TestParamInfo<BadInput>& info) {
    std::string name = std::to_string(info.index) + "_";
    for (char ch : info.param.args) name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
    return name;
}

TEST_P(HapticTuneBadInput, ExitsTwoAndNamesTheValue) {
    const auto result = run_command(tune(GetParam().args));
    EXPECT_EQ(result.exit_code, 2) << result.out;
    EXPECT_NE(result.err.find(GetParam().must_name), std::string::npos) << result.err;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, HapticTuneBadInput,
    ::testing::Values(
        BadInput{"size --mass -1 --damping 2 --rate 1000", "-1"},
        BadInput{"size --mass 0 --damping 2 --rate 1000", "0"},
        BadInput{"size --mass 0.1 --damping nan --rate 1000", "nan"},
        BadInput{"size --mass 0.1 --damping 2 --rate -5", "-5"},
        BadInput{"size --mass 0.1 --damping 2 --rate 1000 --model magic", "magic"},
        BadInput{"size --mass 0.1 --damping 2 --rate 1000 --coupling-damping 50", "b_c = 50"},
        BadInput{"size --mass 0.1 --damping 2 --rate 1000 --coupling-damping 1 --optimize-damping",
                 "--optimize-damping"},
        BadInput{"size --mass 0.1 --damping 2", "--rate"},
        BadInput{"size --mass abc --damping 2 --rate 1000", "abc"},
        BadInput{"check --mass 0.1 --damping 2 --rate 1000", "--stiffness"},
        BadInput{"check --mass 0.1 --damping 2 --rate 1000 --stiffness 100 --model exactly",
                 "exactly"},
        BadInput{"size --config /nonexistent.toml", "/nonexistent.toml"}),
    bad_input_name);

// An operator class and a scene: the model they need, and their files' errors.
const std::string kPen = "--mass 0.1 --damping 2 --rate 1000 --stiffness 3000 ";
INSTANTIATE_TEST_SUITE_P(
    Assumptions, HapticTuneBadInput,
    ::testing::Values(
        BadInput{"check " + kPen +
                     "--operator-class " HAPTICD_SOURCE_DIR "/config/operators/pen-grip.toml",
                 "--operator-class needs --model exact: the passive model holds for every "
                 "passive operator"},
        BadInput{"check " + kPen +
                     "--model exact --operator-class " HAPTICD_SOURCE_DIR "/config/hapticd.toml",
                 "has no [operator] table"},
        BadInput{"check " + kPen + "--model exact --operator-class /nonexistent.toml",
                 "/nonexistent.toml: cannot read the operator class file"},
        BadInput{"check " + kPen +
                     "--model encoder --scene " HAPTICD_SOURCE_DIR "/config/scenes/demo-wall.toml",
                 "--scene needs --model passive or exact"},
        BadInput{
            "check " + kPen + "--scene " HAPTICD_SOURCE_DIR "/config/scenes/detent-friction.toml",
            "cannot be checked against its own objects: [[detent]] #1"},
        BadInput{
            "size --mass 0.1 --damping 2 --rate 1000 --optimize-damping --scene " HAPTICD_SOURCE_DIR
            "/config/scenes/demo-wall.toml",
            "--optimize-damping sizes under the passive model against every passive"}),
    bad_input_name);

// Issue 27, item 6: every size answer is a design or an error naming why. A b_c that leaves
// no stiffness gave "stiffness -0" or 0 with exit 0; a PI loop of zero ran 18 s and returned a
// 4.2e-7 kg coupling mass.
INSTANTIATE_TEST_SUITE_P(
    Issue27, HapticTuneBadInput,
    ::testing::Values(
        BadInput{"size --mass 0.1 --damping 2 --rate 1000 --delay 0.001 --coupling-damping 2",
                 "b_c = 2 N s/m leaves no stiffness"},
        BadInput{"size --mass 0.1 --damping 2 --rate 1000 --model exact --coupling-damping 3",
                 "b_c must be below 2 N s/m"},
        BadInput{"size --mass 0.1 --damping 2 --rate 1000 --model exact --coupling-damping 1e5",
                 "b_c must be below 2 N s/m"},
        BadInput{"size --mass 2 --damping 5 --rate 1000 --display admittance --kp 0 --ki 0 "
                 "--model exact",
                 "--kp 0 with --ki 0"}),
    bad_input_name);

TEST(HapticTuneConfig, AClassWithAVanishingHandNamesTheFileAndTheKey) {
    const ScratchDir dir;
    const std::string path =
        dir.write("hands.toml",
                  "[operator]\nhand_mass = 1e-300\ngrip_stiffness = [0, 3000]\ngrip_damping = "
                  "[2, 30]\narm_stiffness = [0, 1000]\narm_damping = [0, 20]\n");
    const auto result =
        run_command(tune("check " + kPen + "--model exact --operator-class " + path));
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.err.find(path + ": [operator] hand_mass = 1e-300 kg is out of range: "
                                     "allowed >= 1e-06 kg and <= 1000 kg"),
              std::string::npos)
        << result.err;
}

// Issue 27, item 3: at half a period of delay the exact model sized 1777 N/m; it now gives the
// proven passive limit, 1600 N/m (k_c <= 2b/(τ² T), τ² = 2.5), and says what proves it.
TEST(HapticTuneSize, TheExactModelSizesNoFurtherThanThePassiveProof) {
    const auto result = run_command(
        tune("size --mass 0.1 --damping 2 --rate 1000 --delay 0.0005 --model exact --json"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const json out = json::parse(result.out);
    EXPECT_LE(out.at("stiffness").get<double>(), 1600.0);
    EXPECT_GE(out.at("stiffness").get<double>(), 1599.0);
    EXPECT_EQ(out.at("proof").get<std::string>(), "the passive port condition");
}

// Issue 27, item 3's other half: at a fraction of a period of delay the exact model found no
// operator that reaches the passive bound; each alias now gets its own worst reactance
// (alias_shaped_operator), and 3 % past the bound such an operator grows.
TEST(HapticTuneSize, AFractionalDelaysWitnessIsFoundThreePercentPastTheBound) {
    for (const std::string delay : {"0.00025", "0.0005", "0.0015"}) {
        SCOPED_TRACE("delay " + delay);
        const auto result = run_command(tune("size --mass 0.1 --damping 2 --rate 1000 --delay " +
                                             delay + " --model exact --json"));
        ASSERT_EQ(result.exit_code, 0) << result.err;
        const json witness = json::parse(result.out).at("witness");
        EXPECT_DOUBLE_EQ(witness.at("factor").get<double>(), 1.03);
        EXPECT_TRUE(witness.at("found").get<bool>()) << witness.dump();
        EXPECT_GT(witness.at("search").at("worst_spectral_radius").get<double>(), 1.0 + 1e-7);
        EXPECT_NE(witness.at("search")
                      .at("worst_operator")
                      .get<std::string>()
                      .find("on its worst point for"),
                  std::string::npos)
            << witness.dump();
    }
}

TEST(HapticTuneCheck, AClassAndASceneAreStatedInTheVerdict) {
    const auto result =
        run_command(tune("check " + kPen + "--coupling-damping 1 --model exact --operator-class " +
                         HAPTICD_SOURCE_DIR + "/config/operators/pen-grip.toml --json"));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const json out = json::parse(result.out);
    EXPECT_TRUE(out.at("unconditionally_stable").get<bool>());
    EXPECT_EQ(out.at("holds_for")
                  .get<std::string>()
                  .rfind("the declared operator class (two-mass grasps with m_h 0.1..2 kg", 0),
              0u)
        << out.dump();
    // 3000 N/m at b_c = 1 fails for every passive operator (2000 N/m is the bound).
    EXPECT_EQ(run_command(tune("check " + kPen + "--coupling-damping 1")).exit_code, 1);
    const auto scene = run_command(
        tune("check --mass 0.1 --damping 2 --rate 1000 --stiffness "
             "1200 --delay 0.001 --json --scene " +
             std::string(HAPTICD_SOURCE_DIR) + "/config/scenes/god-object-sphere.toml"));
    ASSERT_EQ(scene.exit_code, 0) << scene.err;
    EXPECT_NE(json::parse(scene.out)
                  .at("holds_for")
                  .get<std::string>()
                  .find("every passive operator and the scene"),
              std::string::npos);
}

TEST(HapticTuneConfig, ErrorsNameTheFileTheKeyAndTheRange) {
    const ScratchDir dir;
    const std::string path = dir.write(
        "bad.toml", "[servo]\nrate_hz = 1000\n[device.model]\nmass = -0.5\ndamping = 2\n");
    const auto result = run_command(tune("size --config " + path));
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_NE(result.err.find(path), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("[device.model] mass = -0.5"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find(">= 0.0001 and <= 1000 (kg)"), std::string::npos) << result.err;
    dir.write("bad.toml", "[device.model]\nmass = 0.1\ndamping = 2\ninertia = 3\n");
    const auto unknown = run_command(tune("size --config " + path + " --rate 1000"));
    EXPECT_EQ(unknown.exit_code, 2);
    EXPECT_NE(unknown.err.find("inertia"), std::string::npos) << unknown.err;
}

TEST(HapticTuneCheck, ExitCodeIsTheVerdict) {
    const auto stable =
        run_command(tune("check --mass 0.1 --damping 2 --rate 1000 --stiffness 3900 --json"));
    EXPECT_EQ(stable.exit_code, 0) << stable.err;
    const json s = json::parse(stable.out);
    EXPECT_TRUE(s.at("unconditionally_stable").get<bool>());
    EXPECT_NEAR(s.at("worst_margin").get<double>(), 4000.0 / 3900.0 - 1.0, 1e-9);
    EXPECT_EQ(s.at("worst_frequency_hz").get<double>(), 0.0);

    const auto unstable =
        run_command(tune("check --mass 0.1 --damping 2 --rate 1000 --stiffness 4100 --json"));
    EXPECT_EQ(unstable.exit_code, 1);
    EXPECT_FALSE(json::parse(unstable.out).at("unconditionally_stable").get<bool>());
}

TEST(HapticTuneCheck, PaperModelAcceptsWhatTheEncoderModelRejects) {
    const std::string design = "check --mass 0.1 --damping 2 --rate 1000 --stiffness 12000";
    EXPECT_EQ(run_command(tune(design + " --model paper")).exit_code, 0);
    EXPECT_EQ(run_command(tune(design + " --model encoder")).exit_code, 1);
}

TEST(HapticTuneCheck, ExactModelNamesTheWorstOperator) {
    const auto result = run_command(
        tune("check --mass 0.1 --damping 2 --rate 1000 --stiffness 16000 --model exact --json"));
    EXPECT_EQ(result.exit_code, 1) << result.err;
    const json j = json::parse(result.out);
    EXPECT_FALSE(j.at("unconditionally_stable").get<bool>());
    EXPECT_LT(j.at("worst_margin").get<double>(), 0.0);
    EXPECT_FALSE(j.at("worst_operator").get<std::string>().empty());
}

// The coupling damper on a filtered velocity: every model sees it through Z_c. With no delay
// the passive bound is k_c T/2 + b_c (1 - a)/(1 + a) <= b, a = exp(-2π f_c T): 3695.78 N/m
// for b_c = 0.5 N s/m on a 100 Hz filter, against 3000 N/m unfiltered.
TEST(HapticTuneVelocityFilter, SizeCheckAndPlotPassItToTheModels) {
    const std::string device = "--mass 0.1 --damping 2 --rate 1000";
    const auto sized = run_command(
        tune("size " + device + " --coupling-damping 0.5 --velocity-filter 100 --json"));
    ASSERT_EQ(sized.exit_code, 0) << sized.err;
    const json s = json::parse(sized.out);
    EXPECT_NEAR(s.at("stiffness").get<double>(), 3695.78381, 1e-4);
    EXPECT_EQ(s.at("velocity_filter_hz").get<double>(), 100.0);
    EXPECT_NEAR(s.at("binding_frequency_hz").get<double>(), 500.0, 1e-6);
    EXPECT_TRUE(s.at("exact_check").at("stable").get<bool>());
    const auto unfiltered = run_command(tune("size " + device + " --coupling-damping 0.5 --json"));
    ASSERT_EQ(unfiltered.exit_code, 0) << unfiltered.err;
    EXPECT_NEAR(json::parse(unfiltered.out).at("stiffness").get<double>(), 3000.0, 1e-4);
    EXPECT_EQ(json::parse(unfiltered.out).at("velocity_filter_hz").get<double>(), 0.0);

    const std::string design = "check " + device + " --stiffness 3600 --coupling-damping 0.5";
    EXPECT_EQ(run_command(tune(design)).exit_code, 1);
    for (const char* model : {"passive", "exact"}) {
        const auto check =
            run_command(tune(design + " --velocity-filter 100 --json --model " + model));
        EXPECT_EQ(check.exit_code, 0) << model << check.err;
        EXPECT_EQ(json::parse(check.out).at("velocity_filter_hz").get<double>(), 100.0);
    }
    const auto encoder =
        run_command(tune(design + " --velocity-filter 100 --json --model encoder"));
    EXPECT_NE(json::parse(encoder.out).at("worst_margin").get<double>(),
              json::parse(run_command(tune(design + " --json --model encoder")).out)
                  .at("worst_margin")
                  .get<double>());

    const auto plot = run_command(tune("plot " + device +
                                       " --stiffness 3600 --coupling-damping 0.5 "
                                       "--velocity-filter 100 --json --points 50"));
    ASSERT_EQ(plot.exit_code, 0) << plot.err;
    const json p = json::parse(plot.out);
    EXPECT_EQ(p.at("design").at("velocity_filter_hz").get<double>(), 100.0);
    EXPECT_TRUE(p.at("models").at("passive").at("unconditionally_stable").get<bool>());
    EXPECT_NE(p.at("title").get<std::string>().find("100 Hz velocity filter"), std::string::npos);
}

TEST(HapticTuneVelocityFilter, ReadsItFromAConfigAndRejectsCutoffsOutOfRange) {
    const ScratchDir dir;
    const std::string path =
        dir.write("filter.toml",
                  "[servo]\nrate_hz = 1000\n[device.model]\nmass = 0.1\ndamping = 2\n"
                  "[coupling]\nstiffness = 3600\ndamping = 0.5\nvelocity_filter = 100\n");
    const auto from_file = run_command(tune("check --config " + path + " --json"));
    EXPECT_EQ(from_file.exit_code, 0) << from_file.err;
    EXPECT_EQ(json::parse(from_file.out).at("velocity_filter_hz").get<double>(), 100.0);
    // The flag overrides the file: 0 is no filter, and 3600 N/m at 0.5 N s/m fails.
    EXPECT_EQ(run_command(tune("check --config " + path + " --velocity-filter 0")).exit_code, 1);
    struct Bad {
        const char* args;
        const char* message;
    };
    for (const Bad bad :
         {Bad{"--velocity-filter 500",
              "velocity filter cutoff f_c = 500 Hz is out of range: allowed 0 (no "
              "filter) or 1 Hz <= f_c < 500 Hz"},
          Bad{"--velocity-filter 0.5", "f_c = 0.5 Hz is out of range"},
          Bad{"--velocity-filter -3", "--velocity-filter: value -3 is out of range"},
          Bad{"--velocity-filter abc", "--velocity-filter: value 'abc' is not a number"}}) {
        for (const char* command : {"size", "check --stiffness 100", "plot --json"}) {
            const auto r = run_command(
                tune(std::string(command) + " --mass 0.1 --damping 2 --rate 1000 " + bad.args));
            EXPECT_EQ(r.exit_code, 2) << command << " " << bad.args;
            EXPECT_NE(r.err.find(bad.message), std::string::npos) << command << ": " << r.err;
        }
    }
}

TEST(HapticTune, HelpExitsZero) {
    const auto result = run_command(tune("size --help"));
    EXPECT_EQ(result.exit_code, 0);
    EXPECT_NE(result.out.find("--optimize-damping"), std::string::npos);
}

}  // namespace
}  // namespace hapticd
