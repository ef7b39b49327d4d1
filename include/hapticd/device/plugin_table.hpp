// A device plugin's own table, [device.<plugin>], as the plugin reads it in open(): from the
// document DeviceConfig hands over (the config file's own text, so that every message
// carries the line of the key in that file, as a scene's do), with the one field reader of
// input/table_reader.hpp. Used outside the tick only (it allocates and throws
// input::ConfigError, a std::runtime_error).
#pragma once

#include <toml++/toml.h>

#include <string>
#include <string_view>

#include "hapticd/device/device.hpp"
#include "hapticd/input/table_reader.hpp"

namespace hapticd::device {

using input::TableReader;

class PluginTable {
  public:
    /// Parses config.plugin_table_toml and finds the table at config.plugin_table_path (the
    /// whole document when that is empty; none is an empty table). Messages name
    /// config.source and the table as [device.<plugin>], and `doc` (the plugin's document)
    /// when a key is unknown.
    PluginTable(const DeviceConfig& config, std::string_view plugin, std::string doc);
    PluginTable(const PluginTable&) = delete;
    PluginTable& operator=(const PluginTable&) = delete;

    TableReader& reader() noexcept { return reader_; }

  private:
    toml::table document_;
    toml::table empty_;
    TableReader reader_;
};

}  // namespace hapticd::device
