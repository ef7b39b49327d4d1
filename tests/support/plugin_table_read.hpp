// A device plugin's own table, [device.<plugin>], read in a test as the plugin reads it in
// open(): the TOML through a PluginTable (messages name the config file and the key's line),
// the plugin's settings reader, then finish(), so that a key it did not read is refused. For
// the transports' settings tests (usb, hid), which need no device.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "hapticd/device/device.hpp"
#include "hapticd/device/plugin_table.hpp"

namespace hapticd::testing {

/// Where a plugin's table comes from in the messages: the plugin's name, its document, the
/// config file.
struct PluginTableSource {
    std::string_view plugin;  ///< "usb": the table is [device.usb]
    std::string doc;          ///< named when a key is unknown, e.g. "docs/transport-usb.md"
    std::string config;       ///< the config file's name in messages
};

/// What `read(reader, config)` returns for the table `toml`, after finish(). `config` is
/// the DeviceConfig the table came in (its source, its plugin_table_toml).
template <typename Read>
auto read_plugin_table(const PluginTableSource& source, const std::string& toml, Read read) {
    device::DeviceConfig config;
    config.source = source.config;
    config.plugin_table_toml = toml;
    device::PluginTable table(config, source.plugin, source.doc);
    device::TableReader& reader = table.reader();
    auto settings = read(reader, config);
    reader.finish();
    return settings;
}

/// The message `read_settings()` throws (a std::runtime_error, as ConfigError is), or
/// `if_none` when it returns.
template <typename ReadSettings>
std::string thrown_message(ReadSettings read_settings, const std::string& if_none) {
    try {
        (void)read_settings();
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return if_none;
}

}  // namespace hapticd::testing
