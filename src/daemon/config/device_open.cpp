#include "hapticd/daemon/device_open.hpp"

#include <exception>
#include <optional>
#include <stdexcept>
#include <string>

namespace hapticd::daemon {
namespace {

/// The refusal of a plugin that cannot be loaded, the loader's reason after the config's key.
ConfigError unloadable(const Config& config, const std::exception& e) {
    return ConfigError(config.source + ": [device] plugin = \"" + config.device.plugin +
                       "\": " + e.what());
}

}  // namespace

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

void check_device_config(const Config& config, UnloadablePlugin if_unloadable, bool lockstep) {
    const device::DeviceConfig table = device_config(config, lockstep);
    std::optional<std::string> refusal;
    try {
        // The message comes back in a string of ours, copied while the plugin was loaded.
        refusal = device::check_plugin_config(config.device.plugin, table);
    } catch (const std::exception& e) {
        if (if_unloadable == UnloadablePlugin::defer) return;
        throw unloadable(config, e);
    }
    if (refusal) throw ConfigError(*refusal);
}

device::DeviceHandle open_device(const Config& config, bool lockstep) {
    device::DeviceHandle device;
    try {
        device = device::load_device(config.device.plugin);
    } catch (const std::exception& e) {
        throw unloadable(config, e);
    }
    // What open() throws is the plugin's: its type and vtable live in the plugin's code, which
    // is unloaded with the handle. Its message is copied here, while the plugin is loaded, and
    // goes on in an exception of ours (rethrowing it would hand the caller an object whose
    // vtable is gone: UBSan's vptr check caught exactly that).
    std::string message;
    try {
        device->open(device_config(config, lockstep));
        return device;
    } catch (const std::exception& e) {
        message = e.what();
    } catch (...) {
        message = config.source + ": [device] plugin = \"" + config.device.plugin +
                  "\": open() threw something that is not a std::exception";
    }
    device->close();
    throw std::runtime_error(message);
}

}  // namespace hapticd::daemon
