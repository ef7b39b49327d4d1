// daemon::check_device_config (device_open.hpp, docs/architecture.md §4.3): the config's
// plugin checks its own [device.<plugin>] table without opening anything, with the message
// its open() gives; a plugin that cannot be loaded is refused with open_device's message, or
// left to open_device.
#include "hapticd/daemon/device_open.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace hapticd::daemon {
namespace {

Config lab(const std::string& plugin, const std::string& table) {
    return parse_config("[device]\nplugin = \"" + plugin + "\"\n[device." + plugin + "]\n" + table,
                        "lab.toml", "/etc/hapticd");
}

/// What check_device_config refused `config` with ("" if it accepted it).
std::string check_refusal(const Config& config,
                          UnloadablePlugin unloadable = UnloadablePlugin::refuse) {
    try {
        check_device_config(config, unloadable);
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "";
}

/// What open_device refused `config` with ("" if it opened).
std::string open_refusal(const Config& config) {
    try {
        open_device(config, /*lockstep=*/true);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

TEST(DaemonDeviceOpen, ABadTableIsRefusedWithOpensMessage) {
    struct Case {
        std::string plugin, table, expect;
    };
    for (const Case& c : {
             Case{"sim", "mass = 0.2\nmas = 1\n",
                  "lab.toml:5: [device.sim] mas = 1 is not a known"},
             Case{"usb", "vid = 0x10000\n",
                  "lab.toml:4: [device.usb] vid = 0x10000 is out of range"},
             Case{"hid", "vid = 0x1209\n", "lab.toml:3: [device.hid] pid is missing"},
             Case{"serial", "baud = 115200\n", "lab.toml:3: [device.serial] port is missing"},
         }) {
        SCOPED_TRACE(c.plugin);
        const Config config = lab(c.plugin, c.table);
        const std::string refusal = check_refusal(config);
        EXPECT_NE(refusal.find(c.expect), std::string::npos) << refusal;
        EXPECT_EQ(refusal, open_refusal(config));  // the same text, word for word
    }
}

TEST(DaemonDeviceOpen, AGoodTableIsAcceptedWithoutOpeningTheDevice) {
    EXPECT_NO_THROW(check_device_config(default_config()));
    // No such port, no such USB or HID device: the table is good, open() would fail later.
    EXPECT_EQ(check_refusal(lab("serial", "port = \"/nonexistent/ttyACM9\"\n")), "");
    EXPECT_NE(open_refusal(lab("serial", "port = \"/nonexistent/ttyACM9\"\n")), "");
    EXPECT_EQ(check_refusal(lab("usb", "vid = 0x1209\npid = 0xfffe\n")), "");
    EXPECT_EQ(check_refusal(lab("hid", "path = \"/nonexistent/hidraw9\"\n")), "");
}

TEST(DaemonDeviceOpen, AnUnloadablePluginIsRefusedOrLeftToOpen) {
    const Config config = lab("nosuchdevice", "");
    const std::string refusal = check_refusal(config);
    EXPECT_EQ(refusal.rfind("lab.toml: [device] plugin = \"nosuchdevice\": device plugin "
                            "'nosuchdevice' not found",
                            0),
              0u)
        << refusal;
    EXPECT_EQ(refusal, open_refusal(config));
    EXPECT_EQ(check_refusal(config, UnloadablePlugin::defer), "");
}

}  // namespace
}  // namespace hapticd::daemon
