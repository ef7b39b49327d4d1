// Internal to the scene loader: typed, range-checked reads of one TOML table, with errors
// that name the file, line, table, key, value and allowed range (scene.hpp has the format).
#pragma once

#include <toml++/toml.h>

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

#include "hapticd/env/environment.hpp"
#include "hapticd/env/scene.hpp"

namespace hapticd::env::detail {

/// An allowed interval of a number, with its unit for messages.
struct Range {
    double lower;
    bool lower_inclusive;
    double upper;
    bool upper_inclusive;
    std::string_view unit;  ///< "N/m", or "" for a plain number

    [[nodiscard]] bool contains(double value) const noexcept;
    [[nodiscard]] std::string describe() const;  ///< e.g. "> 0 and <= 1e+07 N/m"
};

// The ranges the schema uses (scene.hpp lists them).
inline constexpr double kMaxStiffness_n_per_m = 1e7;
inline constexpr double kMaxDamping_n_s_per_m = 1e5;
inline constexpr double kMaxForce_n = 1e4;
inline constexpr double kMaxLength_m = 100.0;
inline constexpr double kMaxMass_kg = 1e3;
inline constexpr double kMaxCoefficient = 10.0;

[[nodiscard]] std::string format_number(double value);
[[nodiscard]] std::string format_node(const toml::node& node);
[[nodiscard]] std::string format_vector(const Vec3& v, int axes);

/// Reads the keys of one table, after rejecting any key the schema does not allow.
class TableReader {
  public:
    /// `context` names the table in messages: "[scene]", "[[wall]] #2". Throws for the
    /// first key of `table` not in `allowed_keys`, listing the allowed ones.
    TableReader(const toml::table& table, std::string source, std::string context, int axes,
                std::initializer_list<std::string_view> allowed_keys);

    [[nodiscard]] double number(std::string_view key, const Range& range,
                                std::optional<double> default_value = std::nullopt);
    /// An array of exactly `axes` numbers, each within ±kMaxLength_m for coordinates, as a
    /// 3-vector with zeros beyond the axes; `direction` requires it non-zero and normalises.
    [[nodiscard]] Vec3 vector(std::string_view key, bool direction,
                              std::optional<Vec3> default_value = std::nullopt);
    [[nodiscard]] bool boolean(std::string_view key, bool default_value);
    [[nodiscard]] std::string string(std::string_view key,
                                     std::optional<std::string> default_value = std::nullopt);
    /// A SceneError at `key`'s line (or the table's, if the key is absent).
    [[noreturn]] void fail(std::string_view key, const std::string& message) const;
    [[nodiscard]] const toml::table& table() const noexcept { return table_; }
    [[nodiscard]] const std::string& context() const noexcept { return context_; }

  private:
    [[nodiscard]] const toml::node* find(std::string_view key) const;

    const toml::table& table_;
    std::string source_;
    std::string context_;
    int axes_;
};

/// "<source>:<line>: " for a node (just "<source>: " without a line).
[[nodiscard]] std::string where(const std::string& source, const toml::node* node);

}  // namespace hapticd::env::detail
