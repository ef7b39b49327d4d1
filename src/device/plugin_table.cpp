// A plugin's [device.<plugin>] table, read where it is in the config (plugin_table.hpp).
#include "hapticd/device/plugin_table.hpp"

namespace hapticd::device {
namespace {

const toml::table& table_in(const toml::table& document, const toml::table& empty,
                            const DeviceConfig& config) {
    if (config.plugin_table_path.empty()) return document;
    const toml::table* table = input::table_at(document, config.plugin_table_path, config.source);
    return table != nullptr ? *table : empty;
}

}  // namespace

PluginTable::PluginTable(const DeviceConfig& config, std::string_view plugin, std::string doc)
    : document_(input::parse_document(config.plugin_table_toml, config.source)),
      reader_(table_in(document_, empty_, config), config.source, "device." + std::string(plugin),
              0, std::move(doc)) {}

}  // namespace hapticd::device
