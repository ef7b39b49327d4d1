// hapticd and haptic-tune read a config the same way (docs/architecture.md §2.3): for every config
// in config/ and for a set of bad files, `hapticd --config F` and `haptic-tune check --config F`
// give the same verdict with the same message. hapticd logs its start-up check's line and
// haptic-tune check prints the same line as "verdict"; a file one refuses, the other refuses
// with the same message (exit 2 from both).
//
// The first two bad files reproduce what disagreed before: `[coupling] enabled = true` ran
// under hapticd and was an unknown key to haptic-tune; `rate_hz = 50` was analysed by
// haptic-tune and refused by hapticd. So do the bad plugin tables: hapticd refused them when
// it opened the device, haptic-tune never read them.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd {
namespace {

using hapticd::testing::CommandResult;
using hapticd::testing::run_command;

const std::string kSource = HAPTICD_SOURCE_DIR;

std::string quoted(const std::string& path) { return "'" + path + "'"; }

/// What one program said about a config: its verdict line, or the message it refused with.
struct Said {
    int exit_code = -1;
    std::string verdict;  ///< "stability check (...)": the start-up check's line; "" if none
    std::string refusal;  ///< the first error message, without the program's prefix
};

/// The first line of `text` that starts with `prefix`, without it ("" if none).
std::string line_after(const std::string& text, const std::string& prefix) {
    for (std::size_t at = 0; at < text.size();) {
        const std::size_t end = std::min(text.find('\n', at), text.size());
        const std::string line = text.substr(at, end - at);
        if (line.rfind(prefix, 0) == 0) return line.substr(prefix.size());
        at = end + 1;
    }
    return "";
}

Said hapticd_on(const std::string& config) {
    const CommandResult r = run_command(std::string(HAPTICD_BIN) + " --config " + quoted(config) +
                                        " --lockstep --duration 0.01 --no-status");
    Said said;
    said.exit_code = r.exit_code;
    said.verdict = line_after(r.err, "hapticd: stability check (");
    if (said.verdict.empty())
        said.verdict = line_after(r.err, "hapticd: WARNING: stability check (");
    if (!said.verdict.empty()) said.verdict = "stability check (" + said.verdict;
    if (said.verdict.empty()) said.refusal = line_after(r.err, "hapticd: ");
    return said;
}

Said haptic_tune_on(const std::string& config) {
    const CommandResult r =
        run_command(std::string(HAPTIC_TUNE) + " check --json --config " + quoted(config));
    Said said;
    said.exit_code = r.exit_code;
    if (r.exit_code == 0 || r.exit_code == 1) {
        said.verdict = nlohmann::json::parse(r.out).at("verdict").get<std::string>();
    } else {
        said.refusal = line_after(r.err, "haptic-tune: config error: ");
    }
    return said;
}

/// Both programs agree on `config`: the same verdict line (stable: hapticd runs or fails
/// later, on the device, and haptic-tune exits 0; not stable: hapticd refuses to arm with
/// exit 2, haptic-tune exits 1), or the same refusal, exit 2 from both.
void expect_agreement(const std::string& config) {
    SCOPED_TRACE(config);
    const Said daemon = hapticd_on(config);
    const Said tune = haptic_tune_on(config);
    if (!daemon.verdict.empty()) {
        EXPECT_EQ(tune.verdict, daemon.verdict);
        const bool stable = daemon.verdict.find("NOT unconditionally stable") == std::string::npos;
        EXPECT_EQ(tune.exit_code, stable ? 0 : 1) << tune.refusal;
        if (!stable) {
            EXPECT_EQ(daemon.exit_code, 2);
        }
    } else {
        EXPECT_EQ(daemon.exit_code, 2);
        EXPECT_EQ(tune.exit_code, 2);
        EXPECT_FALSE(daemon.refusal.empty());
        EXPECT_EQ(tune.refusal, daemon.refusal);
    }
}

std::vector<std::string> shipped_configs() {
    std::vector<std::string> files = {kSource + "/config/hapticd.toml"};
    for (const char* folder : {"/config/devices", "/config/examples"}) {
        for (const auto& entry : std::filesystem::directory_iterator(kSource + folder)) {
            if (entry.path().extension() == ".toml") files.push_back(entry.path().string());
        }
    }
    return files;
}

TEST(ConfigAgreement, EveryShippedConfigGetsOneVerdict) {
    const std::vector<std::string> files = shipped_configs();
    ASSERT_GE(files.size(), 6u);
    for (const std::string& file : files) expect_agreement(file);
    // The shipped configs with a coupling pass; the device files have none and are refused.
    EXPECT_FALSE(hapticd_on(kSource + "/config/hapticd.toml").verdict.empty());
    EXPECT_NE(haptic_tune_on(kSource + "/config/devices/pen-display.toml")
                  .refusal.find("[coupling] stiffness and damping are both 0"),
              std::string::npos);
}

class ConfigAgreementOn : public ::testing::TestWithParam<std::pair<std::string, std::string>> {};

TEST_P(ConfigAgreementOn, HapticdAndHapticTuneSayTheSame) {
    const hapticd::testing::ScratchDir dir;
    expect_agreement(dir.write("lab.toml", GetParam().second));
}

const std::string kPen = "[device.model]\nmass = 0.1\ndamping = 2\n";
const std::string kWall = "[scene]\nfile = \"" + kSource + "/config/scenes/demo-wall.toml\"\n";

INSTANTIATE_TEST_SUITE_P(
    Files, ConfigAgreementOn,
    ::testing::Values(
        // Disagreed before: hapticd ran it, haptic-tune called enabled an unknown key.
        std::pair{"enabled_true", kPen + "[coupling]\nenabled = true\nstiffness = 3000\n" + kWall},
        // Disagreed before: haptic-tune analysed 50 Hz, hapticd refused it.
        std::pair{"rate_50", "[servo]\nrate_hz = 50\n" + kPen + "[coupling]\nstiffness = 50\n"},
        std::pair{"unknown_key", kPen + "[coupling]\nstiffness = 3000\nstifness = 1\n"},
        std::pair{"unknown_table", kPen + "[coupling]\nstiffness = 3000\n[telemetry]\nx = 1\n"},
        std::pair{"wrong_type", kPen + "[coupling]\nstiffness = \"stiff\"\n"},
        std::pair{"delay_too_long", kPen + "delay = 0.02\n[coupling]\nstiffness = 100\n"},
        std::pair{"bad_safety", kPen + "[coupling]\nstiffness = 3000\n[safety]\nmax_force = 0\n"},
        std::pair{"no_model", "[coupling]\nstiffness = 3000\n"},
        std::pair{"too_stiff", kPen + "[coupling]\nstiffness = 16000\n" + kWall},
        std::pair{"delayed_and_filtered",
                  kPen +
                      "delay = 0.001\n[coupling]\nstiffness = 900\ndamping = 0.2\n"
                      "velocity_filter = 100\n" +
                      kWall},
        std::pair{"paper_model",
                  kPen + "[coupling]\nstiffness = 3000\ncheck = \"paper\"\n" + kWall},
        std::pair{"scene_environments",
                  kPen + "delay = 0.001\n[coupling]\nstiffness = 1200\nenvironments = \"scene\"\n" +
                      kWall},
        std::pair{"operator_class",
                  kPen + "[coupling]\nstiffness = 3000\ndamping = 1\ncheck = \"exact\"\n" + kWall +
                      "[operator]\nhand_mass = [0.1, 2.0]\ngrip_stiffness = [0.0, 3000]\n"
                      "grip_damping = [2.0, 30.0]\narm_stiffness = [0.0, 1000]\n"
                      "arm_damping = [0.0, 20.0]\n"},
        std::pair{"class_without_exact",
                  kPen + "[coupling]\nstiffness = 3000\n[operator]\nhand_mass = 1\n"}),
    [](const auto& param_info) { return param_info.param.first; });

// A plugin's own table ([device.<plugin>]) is read by the plugin (docs/architecture.md §4.3):
// hapticd and haptic-tune both have it checked by the plugin when they read the config, so
// a bad one is refused by both with the plugin's message, naming the file, the line and the
// key. Before, hapticd refused it when it opened the device and haptic-tune never saw it.
struct BadPluginTable {
    std::string name;
    std::string plugin;
    std::string table;   ///< the lines of [device.<plugin>], from line 11 of the file
    std::string expect;  ///< in both messages: "lab.toml:LINE: [device.<plugin>] KEY = VALUE"
    friend void PrintTo(const BadPluginTable& bad, std::ostream* out) { *out << bad.name; }
};

class ConfigAgreementOnPluginTable : public ::testing::TestWithParam<BadPluginTable> {};

TEST_P(ConfigAgreementOnPluginTable, BothRefuseWithThePluginsMessage) {
    const BadPluginTable& bad = GetParam();
    const hapticd::testing::ScratchDir dir;
    // A config that passes every other check: the table is its only fault.
    const std::string config =
        dir.write("lab.toml", "[device]\nplugin = \"" + bad.plugin + "\"\n" + kPen +
                                  "[coupling]\nstiffness = 3000\n" + kWall + "[device." +
                                  bad.plugin + "]\n" + bad.table);
    expect_agreement(config);
    const Said tune = haptic_tune_on(config);
    EXPECT_EQ(tune.exit_code, 2);
    EXPECT_NE(tune.refusal.find(dir.path().string() + "/" + bad.expect), std::string::npos)
        << tune.refusal;
}

INSTANTIATE_TEST_SUITE_P(
    Files, ConfigAgreementOnPluginTable,
    ::testing::Values(
        BadPluginTable{"sim_unknown_key", "sim", "mas = 0.2\n",
                       "lab.toml:11: [device.sim] mas = 0.2 is not a known key"},
        BadPluginTable{"sim_out_of_range", "sim", "mass = -1\n",
                       "lab.toml:11: [device.sim] mass = -1 is out of range"},
        BadPluginTable{"sim_wrong_type", "sim", "mass = \"heavy\"\n",
                       "lab.toml:11: [device.sim] mass = \"heavy\""},
        BadPluginTable{"sim_nested", "sim", "[device.sim.faults]\ndrop_probability = 2\n",
                       "lab.toml:12: [device.sim.faults] drop_probability = 2 is out of range"},
        BadPluginTable{"usb_unknown_key", "usb", "vid = 0x1209\nvidd = 1\n",
                       "lab.toml:12: [device.usb] vidd = 1 is not a known key"},
        BadPluginTable{"usb_out_of_range", "usb", "vid = 70000\n",
                       "lab.toml:11: [device.usb] vid = 70000 is out of range"},
        BadPluginTable{"usb_wrong_type", "usb", "interface = \"zero\"\n",
                       "lab.toml:11: [device.usb] interface = \"zero\""},
        BadPluginTable{"hid_unknown_key", "hid", "vendor = 1\n",
                       "lab.toml:11: [device.hid] vendor = 1 is not a known key"},
        BadPluginTable{"hid_out_of_range", "hid", "watchdog_ms = 5000\n",
                       "lab.toml:11: [device.hid] watchdog_ms = 5000 is out of range"},
        BadPluginTable{"hid_wrong_type", "hid", "path = 3\n", "lab.toml:11: [device.hid] path = 3"},
        BadPluginTable{"serial_unknown_key", "serial", "port = \"/dev/null\"\nparity = 1\n",
                       "lab.toml:12: [device.serial] parity = 1 is not a known key"},
        BadPluginTable{"serial_out_of_range", "serial",
                       "port = \"/dev/null\"\nreset_wait_ms = 20000\n",
                       "lab.toml:12: [device.serial] reset_wait_ms = 20000 is out of range"},
        BadPluginTable{"serial_wrong_type", "serial", "port = \"/dev/null\"\nexclusive = \"yes\"\n",
                       "lab.toml:12: [device.serial] exclusive = \"yes\""}),
    [](const auto& param_info) { return param_info.param.name; });

// A [device] plugin that cannot be loaded: hapticd refuses it when it opens the device (after
// its start-up check and the output files' checks), haptic-tune when it reads the config
// (it opens no device); both exit 2 with the same message, which names the config and the key.
TEST(ConfigAgreement, APluginThatCannotBeLoadedIsRefusedByBoth) {
    const hapticd::testing::ScratchDir dir;
    const std::string config =
        dir.write("lab.toml", "[device]\nplugin = \"nosuchdevice\"\n" + kPen +
                                  "[coupling]\nstiffness = 3000\n" + kWall);
    const CommandResult daemon =
        run_command(std::string(HAPTICD_BIN) + " --config " + quoted(config) +
                    " --lockstep --duration 0.01 --no-status");
    const std::string refusal = config +
                                ": [device] plugin = \"nosuchdevice\": device plugin "
                                "'nosuchdevice' not found; looked for:";
    EXPECT_EQ(daemon.exit_code, 2);
    EXPECT_NE(daemon.err.find("hapticd: " + refusal + "\n"), std::string::npos) << daemon.err;
    const Said tune = haptic_tune_on(config);
    EXPECT_EQ(tune.exit_code, 2);
    EXPECT_EQ(tune.refusal, refusal);
}

}  // namespace
}  // namespace hapticd
