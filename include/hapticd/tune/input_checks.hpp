// Checks of user-supplied physical parameters. Each failure throws std::invalid_argument
// whose message names the parameter, the value and the allowed range.
#pragma once

#include <string_view>

#include "hapticd/servo/rate.hpp"
#include "hapticd/theory/benchmark.hpp"

namespace hapticd::tune {

void check_positive(std::string_view name, double value, std::string_view unit);
void check_non_negative(std::string_view name, double value, std::string_view unit);
void check_positive_or_infinite(std::string_view name, double value, std::string_view unit);
void check_in_range(std::string_view name, double value, double lo, double hi,
                    std::string_view unit);

// Physical ranges. Every input that reaches a solver or an eigenvalue problem is held to
// one, not merely to "finite": outside them the numbers mean nothing for a haptic device
// and the numerics (matrix exponentials, eigenvalues) lose their footing. The rate's is the
// servo's own, servo::kRateRange (check_rate).
inline constexpr double kMinDeviceMassKg = 1e-4, kMaxDeviceMassKg = 1e3;
inline constexpr double kMinDeviceDamping = 1e-4, kMaxDeviceDamping = 1e4;  // N s/m

inline constexpr double kMaxCouplingStiffness = 1e9;  // N/m
inline constexpr double kMaxCouplingDamping = 1e5;    // N s/m
inline constexpr double kMaxDelayPeriods = 10.0;      // loop delay beyond the hold, < this
inline constexpr double kMinVelocityFilterHz = 1.0;   // the damper's velocity filter, or 0

/// m in [1e-4, 1e3] kg, b in [1e-4, 1e4] N s/m.
void check_device(const theory::DeviceModel& device);
/// The servo's own range, servo::kRateRange (>= 100 and <= 20000 Hz): a design is for a
/// rate hapticd runs.
void check_rate(double rate_hz);
/// k_c in [0, 1e9] N/m, b_c in [0, 1e5] N s/m.
void check_coupling_gains(const theory::SpringDamperCoupling& coupling);
/// 0 <= delay < kMaxDelayPeriods periods (and finite).
void check_delay_periods(double delay_periods);
/// The coupling damper's velocity filter cutoff (theory/velocity_filter.hpp): 0 (none), or
/// kMinVelocityFilterHz <= f_c < rate_hz/2 (below Nyquist).
void check_velocity_filter(double cutoff_hz, double rate_hz);

}  // namespace hapticd::tune
