// The device plugin ABI: every plugin is a shared object exporting one C symbol,
//
//     extern "C" const hapticd_device_plugin* hapticd_device_plugin_entry(void);
//
// which returns a static descriptor. The loader (plugin_loader.hpp) checks abi_version
// before it touches anything else, so a plugin built against another ABI is refused with
// a clear message rather than crashing. Bump kDeviceAbiVersion whenever Device, Sample,
// Command, DeviceInfo or DeviceConfig change layout or meaning.
#pragma once

#include <cstdint>

#include "hapticd/device/device.hpp"

namespace hapticd::device {
inline constexpr std::uint32_t kDeviceAbiVersion = 2;
}  // namespace hapticd::device

extern "C" {

struct hapticd_device_plugin {
    std::uint32_t abi_version;                  ///< must equal hapticd::device::kDeviceAbiVersion
    const char* name;                           ///< the plugin's name, e.g. "sim"
    const char* description;                    ///< one line for `hapticd --list-plugins`
    hapticd::device::Device* (*create)();       ///< a new, unopened device
    void (*destroy)(hapticd::device::Device*);  ///< deletes what create() returned
};

/// The one symbol a plugin exports.
const hapticd_device_plugin* hapticd_device_plugin_entry(void);
}

#define HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL "hapticd_device_plugin_entry"
