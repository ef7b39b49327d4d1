// Opening the configured device: load its plugin and hand it the config's device settings
// and its own [device.<plugin>] table. One path for the run, the identification run and the
// link diagnosis (docs/architecture.md §2.8).
#pragma once

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/device/plugin_loader.hpp"

namespace hapticd::daemon {

/// What the plugin's open() receives from the config: axes, rate, the clock, and the
/// plugin's table with the config file's text, so that its messages carry lines.
device::DeviceConfig device_config(const Config& config, bool lockstep);

/// Loads [device] plugin and opens it. Throws ConfigError naming the config file and the
/// plugin when the plugin cannot be loaded; std::runtime_error with open()'s message (a bad
/// table, or why the device could not be opened) after closing the device, so that it is left
/// at zero force. Nothing the plugin threw outlives the plugin.
device::DeviceHandle open_device(const Config& config, bool lockstep);

}  // namespace hapticd::daemon
