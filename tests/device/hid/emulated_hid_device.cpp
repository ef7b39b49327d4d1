// One reference device behind an emulated hidraw node (emulated_hid_device.hpp).
#include "emulated_hid_device.hpp"

#include <cstdio>

namespace hapticd::testing {

EmulatedHidDevice::EmulatedHidDevice(const device::protocol::EmulatorConfig& device,
                                     const HidrawNodeSpec& node)
    : config_(device), spec_(node) {
    node_ = testbed_.plug(spec_);
    server_ = std::make_unique<HidDeviceServer>(testbed_.master_fd(node_), config_);
}

EmulatedHidDevice::~EmulatedHidDevice() { unplug(); }

void EmulatedHidDevice::unplug() {
    if (server_ == nullptr) return;
    server_->stop();
    testbed_.unplug(node_);
    server_.reset();
}

void EmulatedHidDevice::replug(int hidraw_number) {
    unplug();
    spec_.hidraw_number = hidraw_number;
    node_ = testbed_.plug(spec_);
    server_ = std::make_unique<HidDeviceServer>(testbed_.master_fd(node_), config_);
}

std::string EmulatedHidDevice::devnode() const { return testbed_.devnode(node_); }

std::string EmulatedHidDevice::table_toml() const {
    char text[64];
    std::snprintf(text, sizeof text, "vid = 0x%04x\npid = 0x%04x\n", spec_.vid, spec_.pid);
    return text;
}

}  // namespace hapticd::testing
