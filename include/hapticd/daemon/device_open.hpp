// Opening the configured device: load its plugin and hand it the config's device settings
// and its own [device.<plugin>] table. One path for the run, the identification run and the
// link diagnosis (docs/architecture.md §2.8); and the plugin's check of its table without
// opening anything, for hapticd and haptic-tune alike when they read a config (§4.3).
#pragma once

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/device/plugin_loader.hpp"

namespace hapticd::daemon {

/// What the plugin's open() receives from the config: axes, rate, the clock, and the
/// plugin's table with the config file's text, so that its messages carry lines.
device::DeviceConfig device_config(const Config& config, bool lockstep);

/// What check_device_config() does when [device] plugin cannot be loaded.
enum class UnloadablePlugin {
    refuse,  ///< throw ConfigError with open_device()'s message for it (haptic-tune)
    defer,   ///< return: open_device() refuses it when the device is opened (hapticd)
};

/// Loads [device] plugin and has it check device_config(config, lockstep) as its open()
/// reads it, opening nothing (device::check_plugin_config). Throws ConfigError with the
/// plugin's own message when the table is bad: the same text open_device() would end with
/// (the file, the line, the key, the value and what is allowed). When the plugin cannot be
/// loaded: `unloadable`.
void check_device_config(const Config& config,
                         UnloadablePlugin unloadable = UnloadablePlugin::refuse,
                         bool lockstep = false);

/// Loads [device] plugin and opens it. Throws ConfigError naming the config file and the
/// plugin when the plugin cannot be loaded; std::runtime_error with open()'s message (a bad
/// table, or why the device could not be opened) after closing the device, so that it is left
/// at zero force. Nothing the plugin threw outlives the plugin.
device::DeviceHandle open_device(const Config& config, bool lockstep);

}  // namespace hapticd::daemon
