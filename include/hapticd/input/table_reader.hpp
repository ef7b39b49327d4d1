// The one reader of hapticd's TOML files: the daemon's config (daemon/config.hpp), through
// it haptic-tune's --config, the scenes (env/scene.hpp), operator classes and the device
// plugins' own tables ([device.<plugin>]). A table is read key by key against declared
// fields (fields.hpp); every key it holds that nobody read is refused by finish(). Every
// message has one form,
//
//     FILE:LINE: TABLE KEY = VALUE PROBLEM: allowed ALLOWED
//
//     lab.toml:3: [servo] rate_hz = 50 is out of range: allowed >= 100 and <= 20000 (Hz)
//     lab.toml:9: [device.sim] mass = "heavy" is not a number: allowed > 0 and <= 1000 (kg)
//     lab.toml:4: [servo] rate = 1000 is not a known key: allowed rate_hz, realtime, priority, cpu
//     box.toml:12: [[wall]] #2 normal = [0, 0] is out of range: allowed a non-zero direction
//     lab.toml:6: [virtual_mass] mass is missing: required, allowed > 0 and <= 1000 (kg)
//
// with the line of the value (of the table, for a key that is missing), the table as it is
// written in the file ([servo], [[wall]] #2 for the second of an array of tables) and the
// value as TOML writes it. Outside the tick only: it allocates and throws ConfigError.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/input/config_error.hpp"
#include "hapticd/input/field_list.hpp"
#include "hapticd/input/fields.hpp"

namespace hapticd::input {

/// A TOML value on one line as messages show it: strings quoted, arrays in brackets, a
/// table as {...}, a float that looks like an integer with ".0" (so 115200.0 is told apart
/// from 115200).
[[nodiscard]] std::string format_value(const toml::node& node);

/// "SOURCE:LINE: " for a node with a position, "SOURCE: " without.
[[nodiscard]] std::string where(std::string_view source, const toml::node* node);

class TableReader {
  public:
    /// `table`, read from `source` (the file name in messages). `path` is the table's dotted
    /// name ("servo", "device.sim.human"; "" for the top level of the file) and `index` its
    /// 1-based place in an array of tables ([[wall]] #2), 0 when it is not in one. `doc`, if
    /// any, is the document that lists the table's keys, named when a key is unknown.
    TableReader(const toml::table& table, std::string source, std::string path, int index = 0,
                std::string doc = "");
    /// A reader of `table`, the sub-table at `key` (the `index`th of an array of tables
    /// there, from 1), with this one's source and document.
    [[nodiscard]] TableReader nested(const toml::table& table, std::string_view key,
                                     int index = 0) const;

    /// The declared fields. Absent: the default; with no default, read() throws (the key
    /// is required) and read_optional() returns none.
    double read(const Number& field);
    std::optional<double> read_optional(const Number& field);
    std::int64_t read(const Integer& field);
    std::optional<std::int64_t> read_optional(const Integer& field);
    bool read(const Flag& field);
    std::string read(const Text& field);
    std::optional<std::string> read_optional(const Text& field);
    template <typename E>
    E read(const Choice<E>& field) {
        const toml::node* node = get(field.key);
        if (node == nullptr) return field.default_value;
        const auto* text = node->as_string();
        const std::optional<E> value =
            text != nullptr ? field.parse(text->get()) : std::optional<E>();
        if (!value) fail(field.key, "is not allowed", field.describe());
        return *value;
    }
    /// A time in seconds from 0 to below `max_periods` periods at `rate_hz` (a loop delay),
    /// checked in periods as the stability models check it (delay x rate < max_periods, so
    /// that rounding cannot pass here and fail there). Absent: 0. Every refusal says
    /// "allowed >= 0 and < MAX (s: N periods at [servo] rate_hz = RATE)".
    double read_periods(std::string_view key, double max_periods, double rate_hz);
    /// A number that is part of a value (an element of an array at `key`), in `range`.
    double number(const toml::node& node, std::string_view key, const Range& range) const;

    /// The raw node at `key`, or null; the key is known from now on.
    const toml::node* get(std::string_view key);
    /// True when the table holds `key` (it stays unknown until read).
    bool has(std::string_view key) const;
    /// The sub-table at `key`, or null when absent; anything but a table is an error.
    const toml::table* subtable(std::string_view key);
    /// The array of tables at `key` ([[key]]), or null when absent.
    const toml::array* array_of_tables(std::string_view key);

    /// Throws "WHERE TABLE KEY = VALUE PROBLEM: allowed ALLOWED" (without "= VALUE" when
    /// the key is absent, at the table's line).
    [[noreturn]] void fail(std::string_view key, std::string_view problem,
                           std::string_view allowed) const;
    /// Throws "WHERE TABLE KEY MESSAGE", for what no "allowed" says better.
    [[noreturn]] void fail(std::string_view key, std::string_view message) const;
    /// Throws "WHERE TABLE MESSAGE" at the table's line.
    [[noreturn]] void fail_table(std::string_view message) const;
    /// Refuses the first key that nothing read, listing the ones that were.
    void finish() const;
    /// Refuses, before anything is read, every key but `keys` (the table's schema, for a
    /// table with required keys): a misspelt key is then named as unknown, not as missing.
    void only(std::initializer_list<std::string_view> keys);

    /// "[servo]", "[[wall]] #2", or "" for the top level.
    [[nodiscard]] std::string name() const;
    /// "[servo] rate_hz": the key as messages name it.
    [[nodiscard]] std::string name(std::string_view key) const;
    /// The dotted name of the sub-table at `key` ("device.sim" in [device]).
    [[nodiscard]] std::string path(std::string_view key) const;
    [[nodiscard]] const std::string& source() const noexcept { return source_; }
    [[nodiscard]] const toml::table& contents() const noexcept { return table_; }

  private:
    enum class Kind { key, table, array_of_tables };
    void mark(std::string_view key, Kind kind);
    [[nodiscard]] std::string prefix(const toml::node* node) const;

    const toml::table& table_;
    std::string source_;
    std::string path_;
    int index_ = 0;
    std::string doc_;
    std::vector<std::pair<std::string, Kind>> known_;
};

namespace detail {

inline void read_into(TableReader& r, const Number& f, double& out) { out = r.read(f); }
inline void read_into(TableReader& r, const Number& f, std::optional<double>& out) {
    out = r.read_optional(f);
}
inline void read_into(TableReader& r, const Integer& f, std::int64_t& out) { out = r.read(f); }
inline void read_into(TableReader& r, const Integer& f, int& out) {
    out = static_cast<int>(r.read(f));  // every Integer the lists bind to an int is an int's
}
inline void read_into(TableReader& r, const Integer& f, std::optional<int>& out) {
    const std::optional<std::int64_t> value = r.read_optional(f);
    out = value ? std::optional(static_cast<int>(*value)) : std::nullopt;
}
inline void read_into(TableReader& r, const Flag& f, bool& out) { out = r.read(f); }
inline void read_into(TableReader& r, const Text& f, std::string& out) { out = r.read(f); }
inline void read_into(TableReader& r, const Text& f, std::optional<std::string>& out) {
    out = r.read_optional(f);
}
template <typename E>
void read_into(TableReader& r, const Choice<E>& f, E& out) {
    out = r.read(f);
}

}  // namespace detail

/// Reads every field of `list` into `out`, in the list's order, but those the section reads
/// itself (read_by_section). Does not finish() the table: the section's own checks follow.
template <typename Struct, typename... Bounds>
void read_fields(TableReader& reader, Struct& out, const FieldList<Struct, Bounds...>& list) {
    std::apply(
        [&](const auto&... bound) {
            ((read_by_section(bound.field) ? void()
                                           : detail::read_into(reader, bound.field, bound.in(out))),
             ...);
        },
        list.fields);
}

/// The document of a file: held to the bounds of text_input.hpp, then parsed. A syntax
/// error is "SOURCE:LINE:COLUMN: TOML syntax error: ..." (ConfigError).
[[nodiscard]] toml::table parse_document(std::string_view text, const std::string& source);

/// The sub-table at the dotted `path` of `document` ("device.sim"), or null when there is
/// none. A part that is not a table is an error naming `source`.
[[nodiscard]] const toml::table* table_at(const toml::table& document, std::string_view path,
                                          const std::string& source);

}  // namespace hapticd::input
