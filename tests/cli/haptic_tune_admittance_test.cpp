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
    // For the impedance display --model exact is a bisection on the exact check: at b_c = 0
    // the device alone binds, just above 2b/T, and the verdict says what it holds for.
    const auto impedance =
        run_command(tune("size --mass 0.1 --damping 2 --rate 1000 --model exact --json"));
    ASSERT_EQ(impedance.exit_code, 0) << impedance.err;
    const json k = json::parse(impedance.out);
    EXPECT_GE(k.at("stiffness").get<double>(), 4000.0);
    EXPECT_LT(k.at("stiffness").get<double>(), 4100.0);
    EXPECT_EQ(k.at("holds_for").get<std::string>(),
              "every passive operator and every passive environment");
}

}  // namespace
}  // namespace hapticd
