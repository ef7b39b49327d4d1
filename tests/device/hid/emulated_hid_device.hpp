// A test fixture: one USB HID device running the reference device behind an emulated hidraw
// node, reached through the real hidapi hidraw backend (umockdev_hidraw.hpp for the node,
// hid_device_server.hpp for the device). Reusable by any test that needs a `hid` device:
//
//     hapticd::testing::EmulatedHidDevice device;          // /dev/hidraw0, 1209:4841
//     config.plugin_table_toml = device.table_toml();      // vid = 0x1209, pid = 0x4841
//     device.server().with_device([](auto& d) { d.faults().corrupt_crc = 1; });
//     device.unplug();  device.replug(1);                   // gone, back as /dev/hidraw1
//
// The process must run under libumockdev-preload (tests/device/hid/CMakeLists.txt runs the
// test executables through umockdev-wrapper); child processes inherit the preload and the
// testbed ($UMOCKDEV_DIR), so a hapticd started by the test sees the device too.
#pragma once

#include <memory>
#include <string>

#include "hapticd/device/protocol/device_emulator.hpp"
#include "hid_device_server.hpp"
#include "pen_display_emulator.hpp"  // the device by default: serial EMU-0001
#include "umockdev_hidraw.hpp"

namespace hapticd::testing {

class EmulatedHidDevice {
  public:
    explicit EmulatedHidDevice(
        const device::protocol::EmulatorConfig& device = pen_display_emulator(),
        const HidrawNodeSpec& node = {});
    ~EmulatedHidDevice();

    EmulatedHidDevice(const EmulatedHidDevice&) = delete;
    EmulatedHidDevice& operator=(const EmulatedHidDevice&) = delete;

    /// The device goes away: the server stops, the sysfs tree and the node are removed, the
    /// pty hangs up (a client sees POLLHUP, EIO). Idempotent.
    void unplug();
    /// It comes back, power-cycled (a new reference device of the same configuration: no
    /// session, zero force, its physics from the start), as /dev/hidraw<hidraw_number>.
    void replug(int hidraw_number);

    bool plugged() const { return server_ != nullptr; }
    std::string devnode() const;
    HidDeviceServer& server() { return *server_; }
    UmockdevHidraw& testbed() { return testbed_; }
    const device::protocol::EmulatorConfig& device_config() const { return config_; }
    /// The [device.hid] keys that select it: "vid = 0x1209\npid = 0x4841\n".
    std::string table_toml() const;

  private:
    UmockdevHidraw testbed_;
    device::protocol::EmulatorConfig config_;
    HidrawNodeSpec spec_;
    int node_ = -1;
    std::unique_ptr<HidDeviceServer> server_;
};

}  // namespace hapticd::testing
