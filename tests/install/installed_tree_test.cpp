// The installed tree: `cmake --install` of this build into a scratch prefix, then the
// installed executables run from there while the build tree exists beside them. They must
// use the installation's plugins, scripts and data only (install/layout.hpp), and every
// file a service needs must be in place (docs/install.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

namespace fs = std::filesystem;

class InstalledTree : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        scratch_ = std::make_unique<ScratchDir>();
        prefix_ = scratch_->file("prefix");
        const CommandResult install =
            run_command(std::string(HAPTICD_TEST_CMAKE) +
                        " --install " HAPTICD_TEST_BUILD_DIR " --prefix " + prefix_);
        install_exit_ = install.exit_code;
        install_output_ = install.out + install.err;
    }
    static void TearDownTestSuite() { scratch_.reset(); }

    void SetUp() override { ASSERT_EQ(install_exit_, 0) << install_output_; }

    /// An installed executable, run with no plugin path of the caller's.
    static CommandResult run_installed(const std::string& command) {
        return run_command("env -u HAPTICD_PLUGIN_PATH -u HAPTICD_CHART_SCRIPT " + prefix_ +
                           "/bin/" + command);
    }
    static std::string installed(const std::string& relative) { return prefix_ + "/" + relative; }

    static inline std::unique_ptr<ScratchDir> scratch_;
    static inline std::string prefix_;
    static inline int install_exit_ = -1;
    static inline std::string install_output_;
};

TEST_F(InstalledTree, HapticdUsesTheInstalledPluginsOnlyWithTheBuildTreePresent) {
    ASSERT_TRUE(fs::is_directory(HAPTICD_TEST_BUILD_PLUGIN_DIR));
    const CommandResult listing = run_installed("hapticd --list-plugins");
    ASSERT_EQ(listing.exit_code, 0) << listing.err;
    const std::string plugin_dir = installed(HAPTICD_TEST_PLUGIN_INSTALL_DIR);
    int plugins = 0;
    std::istringstream lines(listing.out);
    for (std::string line; std::getline(lines, line); ++plugins) {
        EXPECT_NE(line.find("\t" + plugin_dir + "/hapticd-device-"), std::string::npos) << line;
        EXPECT_EQ(line.find(HAPTICD_TEST_BUILD_PLUGIN_DIR), std::string::npos) << line;
        EXPECT_EQ(line.find("unusable"), std::string::npos) << line;
    }
    EXPECT_EQ(plugins, 4) << listing.out;  // sim, usb, hid, serial
    for (const char* kind : {"sim", "usb", "hid", "serial"}) {
        EXPECT_NE(listing.out.find(std::string(kind) + "\t" + plugin_dir), std::string::npos)
            << kind << "\n"
            << listing.out;
    }
}

TEST_F(InstalledTree, TheInstalledHapticdRunsItsEmbeddedDefault) {
    const CommandResult run = run_installed("hapticd --lockstep --duration 1 --summary -");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json summary = nlohmann::json::parse(run.out);
    EXPECT_EQ(summary["ticks"], 1000);
    EXPECT_EQ(summary["version"], HAPTICD_TEST_VERSION);
    EXPECT_TRUE(summary["config_path"].is_null());
    EXPECT_TRUE(summary["faults"].empty()) << run.out;
}

TEST_F(InstalledTree, TheInstalledDefaultConfigFindsItsSceneFromEtc) {
    const std::string config = installed("etc/hapticd/sim.toml");
    ASSERT_TRUE(fs::is_regular_file(config));
    EXPECT_NE(
        read_file(config).find("file = \"" + installed("share/hapticd/scenes/demo-wall.toml")),
        std::string::npos);
    const CommandResult run =
        run_installed("hapticd --config " + config + " --lockstep --duration 1 --summary -");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json summary = nlohmann::json::parse(run.out);
    EXPECT_EQ(summary["config_path"], config);
    EXPECT_EQ(summary["scene"]["name"], "demo-wall");
    EXPECT_EQ(summary["ticks"], 1000);
    const CommandResult check = run_installed("haptic-tune check --config " + config);
    EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
}

TEST_F(InstalledTree, EveryExecutableSaysItsVersion) {
    for (const char* program : {"hapticd", "haptic-tune", "hapticctl"}) {
        const CommandResult version = run_installed(std::string(program) + " --version");
        EXPECT_EQ(version.exit_code, 0) << program << ": " << version.err;
        EXPECT_EQ(version.out, std::string(program) + " " HAPTICD_TEST_VERSION "\n");
    }
}

TEST_F(InstalledTree, TheTemplateUnitRunsTheInstalledHapticdOnTheInstancesConfig) {
    const std::string unit = read_file(installed("lib/systemd/system/hapticd@.service"));
    ASSERT_FALSE(unit.empty());
    EXPECT_NE(unit.find("\nExecStart=" + installed("bin/hapticd") + " --config " +
                        installed("etc/hapticd") + "/%i.toml "),
              std::string::npos)
        << unit;
    for (const char* line :
         {"\nType=notify\n", "\nWatchdogSec=", "\nRestartPreventExitStatus=2\n", "\nUser=hapticd\n",
          "\nGroup=hapticd\n", "\nSupplementaryGroups=plugdev\n",
          "\nLimitRTPRIO=", "\nLimitMEMLOCK=infinity\n", "\nLogsDirectory=hapticd/%i\n",
          "\nLogsDirectoryMode=0750\n", "\nRuntimeDirectory=hapticd\n",
          "\nRuntimeDirectoryPreserve=yes\n", "\nUMask=0027\n", "\nDevicePolicy=closed\n",
          // the device nodes the plugins open: a Hapkit's or an Uno's tty among them
          "\nDeviceAllow=char-usb_device rw\n", "\nDeviceAllow=char-hidraw rw\n",
          "\nDeviceAllow=char-ttyACM rw\n", "\nDeviceAllow=char-ttyUSB rw\n",
          "summary-{start}.json", " --socket ${RUNTIME_DIRECTORY}/%i.sock\n"}) {
        EXPECT_NE(unit.find(line), std::string::npos) << line;
    }
    EXPECT_EQ(unit.find('@' + std::string("HAPTICD_")), std::string::npos) << unit;
    // A prefix other than /usr keeps its configs there, not below /etc.
    EXPECT_EQ(unit.find("\nConfigurationDirectory="), std::string::npos) << unit;
    EXPECT_NE(unit.find("the configs are in " + installed("etc/hapticd")), std::string::npos)
        << unit;
}

// udev names each device by its serial number and tags it for systemd; the installed drop-in
// binds an instance to the device unit of /dev/hapticd/NAME, and systemd-analyze reads the
// installed unit with it applied without a word (an unknown key would be named).
TEST_F(InstalledTree, AnInstanceCanBeBoundToItsDevice) {
    const std::string rules = read_file(installed("lib/udev/rules.d/70-hapticd.rules"));
    for (const char* line :
         {"ATTR{serial}==\"?*\", TAG+=\"systemd\", SYMLINK+=\"hapticd/usb-$attr{serial}\"\n",
          "ATTRS{serial}==\"?*\", TAG+=\"systemd\", SYMLINK+=\"hapticd/hid-$attr{serial}\"\n",
          "ENV{SYSTEMD_WANTS}+=\"hapticd@lab0.service\""}) {
        EXPECT_NE(rules.find(line), std::string::npos) << line;
    }
    // The service's group may hold /dev/cpu_dma_latency (a line in force, not a comment).
    EXPECT_NE(rules.find("\nKERNEL==\"cpu_dma_latency\", SUBSYSTEM==\"misc\", MODE=\"0660\", "
                         "GROUP=\"hapticd\"\n"),
              std::string::npos);
    const std::string drop_in = installed("share/hapticd/examples/systemd/bind-to-device.conf");
    const std::string text = read_file(drop_in);
    EXPECT_NE(text.find("\nBindsTo=dev-hapticd-%i.device\nAfter=dev-hapticd-%i.device\n"),
              std::string::npos)
        << text;
    const std::string units = scratch_->file("units");
    fs::create_directories(units + "/hapticd@lab0.service.d");
    fs::copy_file(installed("lib/systemd/system/hapticd@.service"), units + "/hapticd@.service");
    fs::copy_file(drop_in, units + "/hapticd@lab0.service.d/bind-to-device.conf");
    const CommandResult verify =
        run_command("cd " + units + " && systemd-analyze verify --man=no ./hapticd@lab0.service");
    EXPECT_EQ(verify.exit_code, 0) << verify.err;
    EXPECT_EQ(verify.err, "");
    EXPECT_EQ(verify.out, "");

    // Its commented lines, which narrow DeviceAllow= to the device's own node, read as clean.
    std::string narrowed;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        if (line.starts_with("#[Service]") || line.starts_with("#DeviceAllow=")) {
            line.erase(0, 1);
        }
        narrowed += line + "\n";
    }
    ASSERT_NE(narrowed.find("\n[Service]\nDeviceAllow=\nDeviceAllow=/dev/hapticd/%i rw\n"),
              std::string::npos)
        << narrowed;
    scratch_->write("units/hapticd@lab0.service.d/bind-to-device.conf", narrowed);
    const CommandResult narrowed_verify =
        run_command("cd " + units + " && systemd-analyze verify --man=no ./hapticd@lab0.service");
    EXPECT_EQ(narrowed_verify.exit_code, 0) << narrowed_verify.err;
    EXPECT_EQ(narrowed_verify.err, "");
    EXPECT_EQ(narrowed_verify.out, "");
}

TEST_F(InstalledTree, TheServiceFilesManPagesAndDataAreInstalled) {
    for (const char* file :
         {"lib/udev/rules.d/70-hapticd.rules", "share/man/man8/hapticd.8",
          "share/man/man1/haptic-tune.1", "share/man/man1/hapticctl.1",
          "share/man/man5/hapticd.toml.5", "lib/sysusers.d/hapticd.conf",
          "share/hapticd/hapticd_chart.py", "share/hapticd/scenes/demo-wall.toml",
          "share/hapticd/devices/pen-display.toml", "share/hapticd/operators/pen-grip.toml",
          "share/hapticd/examples/pantograph-usb.toml"}) {
        EXPECT_TRUE(fs::is_regular_file(installed(file))) << file;
    }
    // The examples name their scenes relative to themselves, as in the source tree.
    EXPECT_TRUE(
        fs::is_regular_file(installed("share/hapticd/examples/../scenes/god-object-sphere.toml")));
}

// The Python client goes where Debian's python3 looks below a prefix other than /usr
// (lib/python3.N/dist-packages), and imports from there alone.
TEST_F(InstalledTree, ThePythonClientImportsFromTheInstall) {
    const CommandResult version =
        run_command("/usr/bin/python3 -c \"import sys; print('%d.%d' % sys.version_info[:2])\"");
    ASSERT_EQ(version.exit_code, 0) << version.err;
    const std::string packages =
        installed("lib/python" + version.out.substr(0, version.out.find('\n')) + "/dist-packages");
    EXPECT_TRUE(fs::is_regular_file(packages + "/hapticd/__init__.py")) << packages;
    EXPECT_TRUE(fs::is_regular_file(packages + "/hapticd/control.py")) << packages;
    const CommandResult imported =
        run_command("cd / && PYTHONPATH=" + shell_quote(packages) +
                    " /usr/bin/python3 -c \"import hapticd; print(hapticd.__file__); "
                    "print(hapticd.instance_socket('lab0'))\"");
    ASSERT_EQ(imported.exit_code, 0) << imported.err;
    EXPECT_EQ(imported.out, packages + "/hapticd/__init__.py\n/run/hapticd/lab0.sock\n");
}

// A lab's own world, built out of the tree against the installed package (find_package(hapticd)
// and hapticd_add_environment_plugin, examples/environment-plugin/), renders in the installed
// hapticd: the example's spring wall in place of the default config's demo wall, force for
// force the same.
TEST_F(InstalledTree, ThePluginExampleBuildsAgainstTheInstalledPackageAndRendersTheDemoWall) {
    EXPECT_TRUE(fs::is_regular_file(installed("include/hapticd/env/plugin_abi.h")));
    const std::string example = HAPTICD_TEST_SOURCE_DIR "/examples/environment-plugin";
    const std::string build = scratch_->file("example-build");
    const CommandResult configured = run_command(
        std::string(HAPTICD_TEST_CMAKE) + " -S " + shell_quote(example) + " -B " +
        shell_quote(build) +
        " -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + shell_quote(prefix_));
    ASSERT_EQ(configured.exit_code, 0) << configured.out << configured.err;
    const CommandResult built =
        run_command(std::string(HAPTICD_TEST_CMAKE) + " --build " + shell_quote(build));
    ASSERT_EQ(built.exit_code, 0) << built.out << built.err;
    ASSERT_TRUE(fs::is_regular_file(build + "/libhapticd-env-spring-wall.so"));

    // The installed default config, once as it is and once with the example's scene.
    const std::string config = read_file(installed("etc/hapticd/sim.toml"));
    const std::string demo_scene = installed("share/hapticd/scenes/demo-wall.toml");
    ASSERT_NE(config.find(demo_scene), std::string::npos);
    std::string with_plugin = config;
    with_plugin.replace(with_plugin.find(demo_scene), demo_scene.size(),
                        example + "/spring-wall.toml");
    const std::string demo_config = scratch_->write("demo.toml", config);
    const std::string plugin_config = scratch_->write("plugin.toml", with_plugin);
    const auto run = [&](const std::string& cfg, const std::string& log, const std::string& env) {
        return run_command("env -u HAPTICD_CHART_SCRIPT " + env + " " + prefix_ +
                           "/bin/hapticd --no-status --lockstep --duration 6 --config " +
                           shell_quote(cfg) + " --log " + shell_quote(scratch_->file(log)));
    };
    const CommandResult demo = run(demo_config, "demo.csv", "-u HAPTICD_PLUGIN_PATH");
    ASSERT_EQ(demo.exit_code, 0) << demo.err;
    const CommandResult plugin = run(plugin_config, "plugin.csv", "HAPTICD_PLUGIN_PATH=" + build);
    ASSERT_EQ(plugin.exit_code, 0) << plugin.err;
    EXPECT_NE(plugin.err.find("scene spring-wall"), std::string::npos) << plugin.err;
    const TelemetryLog a = read_telemetry(scratch_->file("demo.csv"));
    const TelemetryLog b = read_telemetry(scratch_->file("plugin.csv"));
    ASSERT_EQ(a.rows(), b.rows());
    double peak_n = 0.0;
    for (std::size_t i = 0; i < a.rows(); ++i) {
        ASSERT_EQ(a.column("f0_n")[i], b.column("f0_n")[i]) << "row " << i;
        peak_n = std::max(peak_n, std::abs(b.column("f0_n")[i]));
    }
    EXPECT_GT(peak_n, 1.0);  // the default hand pushes 5 mm into the wall
}

}  // namespace
}  // namespace hapticd::testing
