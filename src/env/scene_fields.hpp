// Internal to the scene loader: the ranges of the scene schema (scene.hpp lists them) and
// the one field a scene has of its own, a vector of the scene's axes, read with the one
// field reader (input/table_reader.hpp).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "hapticd/env/environment.hpp"
#include "hapticd/input/table_reader.hpp"

namespace hapticd::env::detail {

using input::Range;
using input::TableReader;

inline constexpr double kMaxStiffness_n_per_m = 1e7;
inline constexpr double kMaxDamping_n_s_per_m = 1e5;
inline constexpr double kMaxForce_n = 1e4;
inline constexpr double kMaxLength_m = 100.0;
inline constexpr double kMaxMass_kg = 1e3;
inline constexpr double kMaxCoefficient = 10.0;

inline constexpr Range kPositiveStiffness{
    .lo = 0.0, .hi = kMaxStiffness_n_per_m, .lo_open = true, .unit = "N/m"};
inline constexpr Range kStiffness{.lo = 0.0, .hi = kMaxStiffness_n_per_m, .unit = "N/m"};
inline constexpr Range kPositiveDamping{
    .lo = 0.0, .hi = kMaxDamping_n_s_per_m, .lo_open = true, .unit = "N s/m"};
inline constexpr Range kDamping{.lo = 0.0, .hi = kMaxDamping_n_s_per_m, .unit = "N s/m"};
inline constexpr Range kPositiveForce{.lo = 0.0, .hi = kMaxForce_n, .lo_open = true, .unit = "N"};
inline constexpr Range kPositiveLength{.lo = 0.0, .hi = kMaxLength_m, .lo_open = true, .unit = "m"};
inline constexpr Range kCoordinate{.lo = -kMaxLength_m, .hi = kMaxLength_m, .unit = "m"};
inline constexpr Range kMass{.lo = 0.0, .hi = kMaxMass_kg, .lo_open = true, .unit = "kg"};
inline constexpr Range kCoefficient{.lo = 0.0, .hi = kMaxCoefficient, .lo_open = true};

[[nodiscard]] std::string format_vector(const Vec3& v, int axes);

/// The vector at `key`: an array of exactly `axes` numbers, each a coordinate (kCoordinate)
/// or, for a `direction`, any finite number with a non-zero length (normalised), as a
/// 3-vector with zeros beyond the axes. Absent: `default_value`, or an error when none.
[[nodiscard]] Vec3 read_vector(TableReader& reader, std::string_view key, int axes, bool direction,
                               std::optional<Vec3> default_value = std::nullopt);

}  // namespace hapticd::env::detail
