#include "hapticd/daemon/device_open.hpp"

#include <exception>

namespace hapticd::daemon {

device::DeviceConfig device_config(const Config& config, bool lockstep) {
    device::DeviceConfig device_config;
    device_config.axes = config.device.axes;
    device_config.rate_hz = config.servo.rate_hz;
    device_config.lockstep = lockstep;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.plugin_table_path = config.device.plugin_table_path;
    device_config.source = config.source;
    return device_config;
}

device::DeviceHandle open_device(const Config& config, bool lockstep) {
    device::DeviceHandle device;
    try {
        device = device::load_device(config.device.plugin);
    } catch (const std::exception& e) {
        throw ConfigError(config.source + ": [device] plugin = \"" + config.device.plugin +
                          "\": " + e.what());
    }
    try {
        device->open(device_config(config, lockstep));
    } catch (...) {
        device->close();
        throw;
    }
    return device;
}

}  // namespace hapticd::daemon
