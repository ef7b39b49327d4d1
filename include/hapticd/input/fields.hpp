// The declaration of one key of a TOML table: its name, its unit and range (or its choices),
// its default and one line of help. Each key of the config, a scene or a plugin's table is
// declared once, next to the code it configures, and read with TableReader
// (table_reader.hpp); a default given here is the only one, and the help is what the
// reference tables print (field_list.hpp). std only: a header that declares fields needs no
// TOML.
//
//     inline constexpr input::Number kMaxForce{
//         "max_force", {.lo = 0.0, .hi = 1e4, .lo_open = true, .unit = "N"}, 10.0,
//         "force saturation (vector norm)"};
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "hapticd/input/range.hpp"

namespace hapticd::input {

/// A real number in `range`. No default: read() requires it, read_optional() may lack it.
struct Number {
    std::string_view key;
    Range range;
    std::optional<double> default_value = std::nullopt;
    std::string_view help = "";
    /// The allowed values in words, where they depend on another key ("0, or >= 1 and <
    /// rate_hz/2 (Hz)") and `range` holds only the unit: the reader checks them itself.
    std::string_view rule = "";

    /// `rule`, or the range: ">= 100 and <= 20000 (Hz)".
    [[nodiscard]] std::string describe() const {
        return rule.empty() ? range.describe() : std::string(rule);
    }
};

/// An integer from lo to hi. Messages print the range as "lo..hi".
struct Integer {
    std::string_view key;
    std::int64_t lo = 0;
    std::int64_t hi = 0;
    std::optional<std::int64_t> default_value = std::nullopt;
    std::string_view unit = "";
    std::string_view help = "";

    [[nodiscard]] bool contains(std::int64_t value) const noexcept {
        return value >= lo && value <= hi;
    }
    /// "1..99", "0..10000 (ms)".
    [[nodiscard]] std::string describe() const;
};

/// true or false.
struct Flag {
    std::string_view key;
    bool default_value = false;
    std::string_view help = "";
};

/// A string; `allowed` says what it must be in messages ("a plugin name or a path").
struct Text {
    std::string_view key;
    std::optional<std::string_view> default_value = std::nullopt;
    bool allow_empty = false;
    std::string_view allowed = "a string";
    std::string_view help = "";
    std::size_t max_bytes = 0;  ///< 0: only the file's own bounds (text_input.hpp)

    /// `allowed`, and the length bound if any: "free text, at most 64 bytes".
    [[nodiscard]] std::string describe() const {
        return std::string(allowed) +
               (max_bytes != 0 ? ", at most " + std::to_string(max_bytes) + " bytes" : "");
    }
};

/// One of a few names, read as the enum (or other small type) `E` that the code uses: a
/// mode string never travels further than the reader. `name(value)` is the one spelling of
/// each value (the enum's to_string), so the names live with the type, not here.
template <typename E>
struct Choice {
    std::string_view key;
    std::span<const E> values;
    std::string_view (*name)(E) = nullptr;
    E default_value{};
    std::string_view help = "";

    [[nodiscard]] std::optional<E> parse(std::string_view text) const {
        for (const E& value : values) {
            if (name(value) == text) return value;
        }
        return std::nullopt;
    }
    /// "\"enforce\", \"warn\" or \"off\"".
    [[nodiscard]] std::string describe() const {
        std::string text;
        for (std::size_t i = 0; i < values.size(); ++i) {
            text += i == 0 ? "" : i + 1 == values.size() ? " or " : ", ";
            text += "\"" + std::string(name(values[i])) + "\"";
        }
        return text;
    }
};

}  // namespace hapticd::input
