// The example configs for real devices (config/examples/) stay valid: the daemon's keys
// parse, the coupling passes the start-up model, and the plugin accepts its table; what
// stops them on a machine without the device is only the device's absence.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/device_open.hpp"
#include "hapticd/daemon/startup_check.hpp"

namespace hapticd::daemon {
namespace {

std::vector<std::string> examples() {
    std::vector<std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(HAPTICD_SOURCE_DIR) +
                                                                 "/config/examples")) {
        if (entry.path().extension() == ".toml") files.push_back(entry.path().string());
    }
    return files;
}

TEST(DaemonExamples, EveryExampleIsAValidConfigWhosePluginAcceptsItsTable) {
    const std::vector<std::string> files = examples();
    ASSERT_GE(files.size(), 3u);
    for (const std::string& file : files) {
        SCOPED_TRACE(file);
        const Config config = load_config(file);
        EXPECT_NE(config.device.plugin, "sim");
        const StartupCheck check = check_coupling_at_startup(config);
        EXPECT_TRUE(check.passed && !check.skipped) << check.describe();
        std::string message;
        try {
            open_device(config, /*lockstep=*/false)->close();
            continue;  // a machine with the device attached
        } catch (const std::exception& e) {
            message = e.what();
        }
        // Refused for the device's absence, never for a key or a value of the example.
        EXPECT_EQ(message.find("is not a known key"), std::string::npos) << message;
        EXPECT_EQ(message.find("is not allowed"), std::string::npos) << message;
        EXPECT_NE(message.find(config.device.plugin), std::string::npos) << message;
    }
}

}  // namespace
}  // namespace hapticd::daemon
