// Loading device plugins (plugin_abi.hpp) by name or by path, outside the tick.
//
// A name ("sim") is looked up as `libhapticd-device-<name>.so`, then `hapticd-device-<name>.so`,
// on the plugins' search path (install/plugin_files.hpp: $HAPTICD_PLUGIN_PATH, then the
// executable's own plugin directory); a string containing '/' is a path and is opened as given. The
// built-in plugins (sim) are shared objects found the same way, so a lab's own device needs no
// rebuild of the daemon.
//
// The loader dlopen()s with RTLD_NOW | RTLD_LOCAL, looks up HAPTICD_DEVICE_PLUGIN_ENTRY_SYMBOL,
// checks abi_version before it reads anything else of the descriptor, then calls create() (or,
// for check_plugin_config, only check_config()). Every failure is a std::runtime_error that
// names the plugin and says why.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/device/device.hpp"

namespace hapticd::device {

/// Destroys a plugin's device with the plugin's own destroy(), then (when the last device of
/// that plugin goes) dlclose()s the library: the code outlives every object it made.
class PluginDeleter {
  public:
    PluginDeleter() = default;
    PluginDeleter(void (*destroy)(Device*), std::shared_ptr<void> library)
        : destroy_(destroy), library_(std::move(library)) {}
    void operator()(Device* device) const noexcept;

  private:
    void (*destroy_)(Device*) = nullptr;
    std::shared_ptr<void> library_;  ///< the dlopen handle; dlclose when the last owner goes
};

/// An unopened device owned together with the library that made it.
using DeviceHandle = std::unique_ptr<Device, PluginDeleter>;

/// Loads the plugin `name_or_path` (see the file comment) and creates one unopened device.
/// Throws std::runtime_error: not found (the message lists every file tried), dlopen's own
/// error text, missing entry symbol, null descriptor, wrong ABI version (both numbers),
/// create() returning null or throwing.
DeviceHandle load_device(std::string_view name_or_path);

/// The buffer check_plugin_config() hands a plugin's check_config() by default, in bytes.
inline constexpr std::size_t kCheckMessageCapacity = 16384;

/// Loads the plugin `name_or_path` as load_device() does and has it check `config` as its
/// open() would read it (hapticd_device_plugin::check_config), creating and opening nothing.
/// Nothing when the plugin accepts the config; else the plugin's message (open()'s), copied
/// into a buffer of ours of `capacity` bytes before the library is closed, so cut to at most
/// capacity - 1 bytes at a UTF-8 character boundary. Throws std::runtime_error as
/// load_device() does when the plugin cannot be loaded.
std::optional<std::string> check_plugin_config(std::string_view name_or_path,
                                               const DeviceConfig& config,
                                               std::size_t capacity = kCheckMessageCapacity);

/// One plugin found on the search path, for `hapticd --list-plugins`.
struct PluginListing {
    std::string name;         ///< from the descriptor (or from the file name when unusable)
    std::string description;  ///< from the descriptor
    std::string path;         ///< the shared object
    std::uint32_t abi_version = 0;
    std::string error;      ///< empty when loadable; else why load_device would refuse it
    bool shadowed = false;  ///< an earlier directory has a plugin of the same name
};

/// Every `(lib)hapticd-device-*.so` on the search path, in search order. Never throws for a
/// bad plugin (it is listed with `error` set); unreadable directories are skipped.
std::vector<PluginListing> list_plugins();

}  // namespace hapticd::device
