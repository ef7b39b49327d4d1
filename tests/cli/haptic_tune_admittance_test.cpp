// haptic-tune size --display admittance, end to end through the real executable: the
// passive model's refusal, (37) held against the exact admittance loop, and the exact sizing.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "run_command.hpp"

namespace hapticd {
namespace {

using hapticd::testing::run_command;
using nlohmann::json;

std::string tune(const std::string& args) { return std::string(HAPTIC_TUNE) + " " + args; }

const std::string kDevice = "size --display admittance --mass 2 --damping 5 --rate 1000 ";

// The default is the passive model, and it has no coupling to give (admittance_passive.hpp):
// exit 2, saying why and what to do instead.
TEST(HapticTuneSizeAdmittance, ThePassiveDefaultExplainsWhyNoCouplingHolds) {
    const auto r = run_command(tune(kDevice + "--kp 2 --ki 0 --json"));
    EXPECT_EQ(r.exit_code, 2) << r.out;
    for (const char* must : {"infeasible", "every passive operator", "anti-aliasing",
                             "--model exact", "resonant aliases"}) {
        EXPECT_NE(r.err.find(must), std::string::npos) << must << "\n" << r.err;
    }
    // A velocity loop stiffer than the device's damping fails at the rigid wall already.
    const auto hot = run_command(tune(kDevice + "--kp 8 --ki 0 --delay 0.001"));
    EXPECT_EQ(hot.exit_code, 2);
    EXPECT_NE(hot.err.find("needs device damping b >= 8"), std::string::npos) << hot.err;
}

// With a second-order force filter the passive model sizes: a pure damper (every finite m_c
// fails at low frequency), named with its filter, and held against the exact sweep.
TEST(HapticTuneSizeAdmittance, TheForceFilterMakesThePassiveModelSize) {
    const auto r = run_command(
        tune(kDevice + "--kp 2 --ki 0 --force-filter 100 --coupling-damping 300 --json"));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const json j = json::parse(r.out);
    EXPECT_EQ(j.at("model"), "passive");
    EXPECT_TRUE(j.at("coupling_mass").is_null());
    EXPECT_EQ(j.at("damping").get<double>(), 300.0);
    EXPECT_EQ(j.at("force_filter").at("cutoff_hz").get<double>(), 100.0);
    EXPECT_EQ(j.at("force_filter").at("order").get<int>(), 2);
    EXPECT_GT(j.at("worst_margin").get<double>(), 0.0);
    EXPECT_TRUE(j.at("exact_check").at("stable").get<bool>());
    EXPECT_NE(j.at("holds_for").get<std::string>().find("every passive operator"),
              std::string::npos);
    // A pure mass: none holds, and the lightest pure damper is named instead.
    const auto mass = run_command(tune(kDevice + "--kp 2 --ki 0 --force-filter 100"));
    EXPECT_EQ(mass.exit_code, 2);
    EXPECT_NE(mass.err.find("no pure-mass coupling"), std::string::npos) << mass.err;
    EXPECT_NE(mass.err.find("lightest pure damper that holds is b_c = "), std::string::npos);
    // A first-order filter is not enough.
    const auto first =
        run_command(tune(kDevice + "--kp 2 --ki 0 --force-filter 100 --force-filter-order 1 "
                                   "--coupling-damping 300"));
    EXPECT_EQ(first.exit_code, 2);
    EXPECT_NE(first.err.find("first-order filter is not enough"), std::string::npos) << first.err;
    // Bad filters name the option, the value and the range.
    const auto zero = run_command(tune(kDevice + "--kp 2 --ki 0 --force-filter 0"));
    EXPECT_EQ(zero.exit_code, 2);
    EXPECT_NE(zero.err.find("--force-filter"), std::string::npos) << zero.err;
    EXPECT_NE(zero.err.find("f_aa = 0 Hz is outside (0, 100000] Hz"), std::string::npos)
        << zero.err;
    const auto damping =
        run_command(tune(kDevice + "--kp 2 --ki 0 --force-filter 100 --force-filter-damping 12"));
    EXPECT_EQ(damping.exit_code, 2);
    EXPECT_NE(damping.err.find("ζ = 12 is outside (0, 10]"), std::string::npos) << damping.err;
}

// (37) under the encoder model is optimistic: its best pair fails the exact admittance loop,
// and size says so and exits 1 (as the impedance display's size does).
TEST(HapticTuneSizeAdmittance, ThirtySevenIsHeldAgainstTheExactLoop) {
    const auto r =
        run_command(tune(kDevice + "--kp 2 --ki 0 --model encoder --optimize-damping --json"));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    const json j = json::parse(r.out);
    EXPECT_EQ(j.at("model"), "encoder");
    EXPECT_GT(j.at("coupling_mass").get<double>(), 0.0);
    EXPECT_GT(j.at("damping").get<double>(), 0.0);
    EXPECT_FALSE(j.at("exact_check").at("stable").get<bool>());
    EXPECT_NE(r.err.find("the exact admittance model finds this design unstable"),
              std::string::npos)
        << r.err;
    const auto skipped =
        run_command(tune(kDevice + "--kp 2 --ki 0 --model encoder --optimize-damping --json "
                                   "--no-exact-check"));
    EXPECT_EQ(skipped.exit_code, 0) << skipped.err;
    EXPECT_FALSE(json::parse(skipped.out).contains("exact_check"));
    // (37) has no delay.
    const auto delayed = run_command(tune(kDevice + "--kp 2 --ki 0 --model paper --delay 0.001"));
    EXPECT_EQ(delayed.exit_code, 2);
    EXPECT_NE(delayed.err.find("--model exact takes it"), std::string::npos) << delayed.err;
}

// --model exact sizes on the exact loop, names the class it holds for, and passes its own
// check; with a delay too.
TEST(HapticTuneSizeAdmittance, TheExactSizingPassesItsCheckAndNamesItsClass) {
    for (const char* delay : {"0", "0.001"}) {
        const auto r = run_command(
            tune(kDevice + "--kp 2 --ki 0 --model exact --json --delay " + std::string(delay)));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const json j = json::parse(r.out);
        EXPECT_EQ(j.at("model"), "exact");
        EXPECT_TRUE(j.at("exact_check").at("stable").get<bool>());
        EXPECT_NEAR(j.at("coupling_mass").get<double>(),
                    j.at("safety_factor").get<double>() * j.at("limit_coupling_mass").get<double>(),
                    1e-9 * j.at("coupling_mass").get<double>());
        EXPECT_TRUE(j.at("damping").is_null());
        EXPECT_NE(j.at("holds_for").get<std::string>().find("not every passive operator"),
                  std::string::npos);
        EXPECT_FALSE(j.at("binding_operator").get<std::string>().empty());
    }
    const auto optimise =
        run_command(tune(kDevice + "--kp 2 --ki 0 --model exact --optimize-damping"));
    EXPECT_EQ(optimise.exit_code, 2);
    EXPECT_NE(optimise.err.find("--optimize-damping"), std::string::npos) << optimise.err;
    // For the impedance display --model exact against every passive operator is the proven
    // passive limit, 2b/T at b_c = 0, and the exact model names an operator unstable 3 % past
    // it (hands-off, the device alone, binds); the verdict says what it holds for.
    const auto impedance =
        run_command(tune("size --mass 0.1 --damping 2 --rate 1000 --model exact --json"));
    ASSERT_EQ(impedance.exit_code, 0) << impedance.err;
    const json k = json::parse(impedance.out);
    EXPECT_GE(k.at("stiffness").get<double>(), 3990.0);
    EXPECT_LE(k.at("stiffness").get<double>(), 4000.0);
    EXPECT_EQ(k.at("proof").get<std::string>(), "the passive port condition");
    EXPECT_TRUE(k.at("witness").at("found").get<bool>());
    EXPECT_EQ(k.at("holds_for").get<std::string>(),
              "every passive operator and every passive environment");
}

}  // namespace
}  // namespace hapticd
