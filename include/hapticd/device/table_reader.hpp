// Reads one TOML table of a device plugin's configuration ([device.<plugin>] and its
// subtables): typed getters that remember which keys were read, and finish() that rejects
// the rest. Every error names the source file, the full key, the value and the allowed
// range, as DESIGN.md asks of configuration errors. Used outside the tick only (it
// allocates and throws std::runtime_error).
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace hapticd::device {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// A numeric range with open or closed ends, printed in error messages.
struct Range {
    double lo = -kInf;
    double hi = kInf;
    bool lo_open = false;
    const char* unit = "";

    bool contains(double x) const;
    std::string describe() const;
};

/// A TOML value as the user wrote it, on one line (for error messages).
std::string printed(const toml::node& node);

class TableReader {
  public:
    /// `prefix` is the table's full key with a trailing dot ("device.sim."); `doc` is the
    /// document that lists the table's keys, named when a key is unknown.
    TableReader(const toml::table& table, std::string prefix, const std::string& source,
                std::string doc);

    [[noreturn]] void fail(std::string_view key, const std::string& what) const;
    [[noreturn]] void fail_value(std::string_view key, const toml::node& node,
                                 const std::string& allowed) const;

    const toml::node* get(std::string_view key);
    bool has(std::string_view key) const { return table_.contains(key); }

    double number(const toml::node& node, std::string_view key, const Range& range) const;
    double number(std::string_view key, double fallback, const Range& range);
    std::int64_t integer(std::string_view key, std::int64_t fallback, std::int64_t lo,
                         std::int64_t hi);
    bool boolean(std::string_view key, bool fallback);
    std::string string(std::string_view key, std::string fallback);
    std::string choice(std::string_view key, std::string fallback,
                       std::initializer_list<const char*> allowed);
    /// A list of times, s, each >= 0.
    std::vector<double> times(std::string_view key);
    const toml::table* subtable(std::string_view key);
    /// Rejects every key not read.
    void finish() const;

    const std::string& prefix() const { return prefix_; }
    const std::string& source() const { return source_; }

  private:
    const toml::table& table_;
    std::string prefix_;
    std::string source_;
    std::string doc_;
    std::set<std::string> used_;
};

/// Parses a plugin table handed over as TOML text (DeviceConfig::plugin_table_toml); throws
/// std::runtime_error naming `source` on a syntax error.
toml::table parse_plugin_table(const std::string& toml_text, const std::string& source);

}  // namespace hapticd::device
