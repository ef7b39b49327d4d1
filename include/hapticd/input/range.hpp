// Allowed ranges and the one message for a value outside one:
//
//     NAME = VALUE is out of range: allowed ALLOWED
//
// e.g. "[servo] rate_hz = 50 is out of range: allowed >= 100 and <= 20000 (Hz)" from the
// config reader (table_reader.hpp), "servo config: rate_hz = 50 is out of range: allowed
// >= 100 and <= 20000 (Hz)" from ServoConfig::is_valid. The readers of files and the checks
// of every library's settings structs (servo, env, tune) share it. std only, outside the
// tick (it allocates).
#pragma once

#include <limits>
#include <string>
#include <string_view>

namespace hapticd::input {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// An interval of finite real numbers with open or closed ends, and its unit.
struct Range {
    double lo = -kInf;
    double hi = kInf;
    bool lo_open = false;        ///< true: lo itself is excluded
    bool hi_open = false;        ///< true: hi itself is excluded
    std::string_view unit = "";  ///< "Hz", "N s/m", or words ("s; 0: wait for ever"); "" none

    /// False for NaN and the infinities, whatever the ends.
    [[nodiscard]] bool contains(double value) const noexcept;
    /// ">= 100 and <= 20000 (Hz)", "> 0 (N)", "<= 0.5 (at most static_coefficient)".
    [[nodiscard]] std::string describe() const;
};

/// A number as every message prints it: six significant digits (the C++ stream default:
/// 1000, 0.001, 2e+09), "nan", "inf".
[[nodiscard]] std::string format_number(double value);
/// A number as a file that is read back prints it: the shortest text that reads back to the
/// same double (std::to_chars: 4000, 0.009, 1e-05), "nan", "inf".
[[nodiscard]] std::string exact_number(double value);
/// "0.1 kg": a number with its unit ("0.1" without one).
[[nodiscard]] std::string format_quantity(double value, std::string_view unit);

/// "NAME = VALUE is out of range: allowed ALLOWED".
[[nodiscard]] std::string out_of_range(std::string_view name, std::string_view value,
                                       std::string_view allowed);
[[nodiscard]] std::string out_of_range(std::string_view name, double value,
                                       std::string_view allowed);
[[nodiscard]] std::string out_of_range(std::string_view name, double value, const Range& range);

/// For `bool is_valid(std::string* error) const` (Ceres-style): stores `message` in *error
/// unless `error` is null, and returns false.
bool invalid(std::string* error, std::string message);

/// Throws std::invalid_argument(out_of_range(name, value, allowed)): for the checks of the
/// libraries' settings structs, whose contract is std::invalid_argument.
[[noreturn]] void reject_out_of_range(std::string_view name, std::string_view value,
                                      std::string_view allowed);
[[noreturn]] void reject_out_of_range(std::string_view name, double value,
                                      std::string_view allowed);
[[noreturn]] void reject_out_of_range(std::string_view name, double value, const Range& range);

}  // namespace hapticd::input
