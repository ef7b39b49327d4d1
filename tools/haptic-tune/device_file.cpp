#include "device_file.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <set>
#include <sstream>

#include "hapticd/input/text_input.hpp"

namespace hapticd::tools {
namespace {

std::optional<double> read_number(const std::string& path, const toml::table* table,
                                  const std::string& table_name, const std::string& key,
                                  bool allow_zero, const char* unit) {
    if (table == nullptr) return std::nullopt;
    const toml::node* node = table->get(key);
    if (node == nullptr) return std::nullopt;
    const std::optional<double> value = node->value<double>();
    std::ostringstream where;
    where << path << ": [" << table_name << "] " << key;
    if (!value || node->is_boolean()) {
        throw ConfigError(where.str() + " must be a number (" + unit + ")");
    }
    if (!std::isfinite(*value) || *value < 0.0 || (!allow_zero && *value == 0.0)) {
        std::ostringstream message;
        message << where.str() << " = " << *value << " is out of range: allowed finite and "
                << (allow_zero ? ">= 0" : "> 0") << " (" << unit << ")";
        throw ConfigError(message.str());
    }
    return value;
}

void reject_unknown_keys(const std::string& path, const toml::table* table,
                         const std::string& table_name, const std::set<std::string>& known) {
    if (table == nullptr) return;
    for (const auto& [key, node] : *table) {
        if (node.is_table()) continue;  // nested tables are checked by their own readers
        if (known.count(std::string(key.str())) == 0) {
            std::string allowed;
            for (const auto& k : known) allowed += (allowed.empty() ? "" : ", ") + k;
            throw ConfigError(path + ": unknown key [" + table_name + "] " +
                              std::string(key.str()) + " (allowed: " + allowed + ")");
        }
    }
}

}  // namespace

DeviceFile read_device_file(const std::string& path) {
    std::string text;
    try {
        text = input::read_text_file(path, "the config file");
    } catch (const input::InputError& e) {
        throw ConfigError(e.what());
    }
    if (const std::string e = input::toml_shape_error(text, path); !e.empty()) {
        throw ConfigError(e);
    }
    toml::table root;
    try {
        root = toml::parse(text, path);
    } catch (const toml::parse_error& error) {
        std::ostringstream message;
        message << path << ":" << error.source().begin.line << ":" << error.source().begin.column
                << ": " << error.description();
        throw ConfigError(message.str());
    }
    const toml::table* model = root["device"]["model"].as_table();
    const toml::table* servo = root["servo"].as_table();
    const toml::table* coupling = root["coupling"].as_table();
    reject_unknown_keys(path, model, "device.model", {"mass", "damping", "delay"});
    reject_unknown_keys(path, coupling, "coupling",
                        {"stiffness", "damping", "velocity_filter", "check", "environments"});
    DeviceFile file;
    file.mass_kg = read_number(path, model, "device.model", "mass", false, "kg");
    file.damping_n_s_per_m = read_number(path, model, "device.model", "damping", false, "N s/m");
    file.delay_s = read_number(path, model, "device.model", "delay", true, "s");
    file.rate_hz = read_number(path, servo, "servo", "rate_hz", false, "Hz");
    file.coupling_stiffness_n_per_m =
        read_number(path, coupling, "coupling", "stiffness", true, "N/m");
    file.coupling_damping_n_s_per_m =
        read_number(path, coupling, "coupling", "damping", true, "N s/m");
    // Its range depends on the rate: resolve_design_input checks it.
    file.velocity_filter_hz =
        read_number(path, coupling, "coupling", "velocity_filter", true, "Hz");
    return file;
}

}  // namespace hapticd::tools
