// A settings struct's field list: each key of its TOML table bound to the member it sets, in
// the spirit of Drake's name-value pairs and ros2_control's generate_parameter_library. The
// list sits beside the struct; TableReader's read_fields() fills the struct from it, and
// rows() gives the reference table (key, allowed values, default, help) that --help texts
// and docs print, so that a key is declared once:
//
//     struct ServoSection { double rate_hz = *kRate.default_value; ... };
//     inline constexpr auto kServoFields = input::fields<ServoSection>(
//         "servo", input::bind(kRate, &ServoSection::rate_hz), ...);
//
// A member may be reached through nested structs (bind(kReconnectSettle,
// &SafetySection::reconnect, &servo::LinkRecoverySettings::settle_s)). A Number with a
// `rule` (allowed values that depend on another key, such as "below Nyquist") is listed for
// the reference but read by its section's own code, which knows the other key. std only.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "hapticd/input/fields.hpp"

namespace hapticd::input {

/// One key bound to a member of `Struct`, through `Members` (pointers to members, outer
/// first).
template <typename Struct, typename Field, typename... Members>
struct Bound {
    Field field;
    std::tuple<Members...> members;

    template <typename S>
    [[nodiscard]] auto& in(S& target) const {
        return std::apply(
            [&target](auto... m) -> auto& { return (target.*....*m); }, members);
    }
};

template <typename Field, typename Outer, typename Struct, typename... Rest>
constexpr Bound<Struct, Field, Outer Struct::*, Rest...> bind(const Field& field,
                                                              Outer Struct::*outer, Rest... rest) {
    return {field, {outer, rest...}};
}

/// The keys of one table (`table` as the file writes it: "servo", "device.model").
template <typename Struct, typename... Bounds>
struct FieldList {
    std::string_view table;
    std::tuple<Bounds...> fields;
};

template <typename Struct, typename... Bounds>
constexpr FieldList<Struct, Bounds...> fields(std::string_view table, Bounds... bounds) {
    return {table, {bounds...}};
}

/// True for a field its section reads itself (field_list.hpp's header comment).
template <typename Field>
constexpr bool read_by_section(const Field& /*field*/) {
    return false;
}
constexpr bool read_by_section(const Number& field) { return !field.rule.empty(); }

/// One row of a reference table.
struct FieldRow {
    std::string table;          ///< "servo"
    std::string key;            ///< "rate_hz"
    std::string allowed;        ///< ">= 100 and <= 20000 (Hz)"
    std::string default_value;  ///< "1000", "\"warn\"", "none", "required"
    std::string help;           ///< one line
};

namespace detail {

template <typename T>
struct is_optional : std::false_type {};
template <typename T>
struct is_optional<std::optional<T>> : std::true_type {};

/// What an absent key means: its default, or none (an optional member), or required.
template <typename Member>
std::string absent(const std::optional<std::string>& default_text) {
    if (default_text) return *default_text;
    return is_optional<Member>::value ? "none" : "required";
}

inline std::string allowed(const Number& f) { return f.describe(); }
inline std::string allowed(const Integer& f) { return f.describe(); }
inline std::string allowed(const Flag& /*f*/) { return "true, false"; }
inline std::string allowed(const Text& f) {
    return f.describe() + ", without control characters";  // the reader refuses them in any
}
template <typename E>
std::string allowed(const Choice<E>& f) {
    return f.describe();
}

inline std::optional<std::string> defaulted(const Number& f) {
    return f.default_value ? std::optional(format_number(*f.default_value)) : std::nullopt;
}
inline std::optional<std::string> defaulted(const Integer& f) {
    return f.default_value ? std::optional(std::to_string(*f.default_value)) : std::nullopt;
}
inline std::optional<std::string> defaulted(const Flag& f) {
    return f.default_value ? "true" : "false";
}
inline std::optional<std::string> defaulted(const Text& f) {
    return f.default_value ? std::optional("\"" + std::string(*f.default_value) + "\"")
                           : std::nullopt;
}
template <typename E>
std::optional<std::string> defaulted(const Choice<E>& f) {
    return "\"" + std::string(f.name(f.default_value)) + "\"";
}

}  // namespace detail

/// The reference rows of `list`, in its order.
template <typename Struct, typename... Bounds>
std::vector<FieldRow> rows(const FieldList<Struct, Bounds...>& list) {
    std::vector<FieldRow> out;
    std::apply(
        [&](const auto&... bound) {
            (out.push_back(
                 FieldRow{.table = std::string(list.table),
                          .key = std::string(bound.field.key),
                          .allowed = detail::allowed(bound.field),
                          .default_value = detail::absent<
                              std::remove_cvref_t<decltype(bound.in(std::declval<Struct&>()))>>(
                              detail::defaulted(bound.field)),
                          .help = std::string(bound.field.help)}),
             ...);
        },
        list.fields);
    return out;
}

}  // namespace hapticd::input
