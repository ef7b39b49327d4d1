// One reference device behind an emulated hidraw node (emulated_hid_device.hpp).
#include "emulated_hid_device.hpp"

#include <cstdio>

namespace hapticd::testing {

device::protocol::EmulatorConfig pen_display_emulator() {
    device::protocol::EmulatorConfig c;
    c.sim.axes = 1;
    c.sim.rate_hz = 1000.0;
    c.sim.mass_kg = 0.1;
    c.sim.damping_n_s_per_m = 2.0;
    c.sim.counts_per_meter = 1e5;
    c.sim.force_limit_n = 20.0;
    c.sim.clock = device::sim::SimClock::lockstep;
    c.serial_number = "EMU-0001";
    return c;
}

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
