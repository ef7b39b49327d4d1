// haptic-tune autotune, the computing half (docs/autotune.md): from a recorded run
// to coupling gains that the `exact` model confirms.
//
//   1. identify every axis of the log (identification.hpp);
//   2. size the coupling of each axis alone with the `passive` model (coupling_sizing.hpp):
//      with the loop's delay, b_c = 0 by default (with no delay the passive optimum), or
//      the optimised pair;
//   3. the binding axis is the one whose bound stiffness is smallest (ties: the lowest
//      index); the coupling is margin x its bound stiffness, with its b_c;
//   4. hold that coupling against the `exact` model on every axis's identified device.
//
// Writing [device.model] and [coupling] into a config is the caller's job (haptic-tune's
// cmd_autotune.cpp, through tools/haptic-tune/config_editor.hpp): the tune layer does not know the
// daemon's config (docs/architecture.md §2.9).
#pragma once

#include <string>
#include <vector>

#include "hapticd/servo/rate.hpp"
#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/telemetry_log.hpp"

namespace hapticd::tune {

/// The default safety margin: the coupling stiffness is 90 % of the largest the `passive`
/// model allows for the identified device, as in the project's example configs. The 10 %
/// covers the identification's error (m and b within 2 %, refused beyond 5 % standard
/// error) and a drift of b of the same order (temperature, pose) before the bound is met.
inline constexpr double kDefaultAutotuneMargin = 0.9;

struct AutotuneOptions {
    /// The servo rate the gains are for ([servo] rate_hz), Hz. Not the log's rate: m and b
    /// are continuous-time, so a log at any rate sizes gains for this one.
    double rate_hz = servo::kDefaultRateHz;
    /// k_c = margin x the binding axis's bound stiffness; in (0, 1].
    double margin = kDefaultAutotuneMargin;
    /// false: b_c = 0. true: the passive model's optimised (k_c, b_c) pair of the binding
    /// axis; the margin scales k_c only. With no delay the optimum is b_c = 0 (against every
    /// passive operator, coupling damping buys no stiffness: docs/stability-models.md);
    /// with a delay it is positive.
    bool optimize_damping = false;
    /// The loop's delay beyond the hold, in periods ([device.model] delay x rate_hz):
    /// 0 <= d < 10. The sizing and the exact check both include it.
    double delay_periods = 0.0;
    /// The coupling damper's velocity filter ([coupling] velocity_filter), Hz; 0: none. The
    /// sizing and the exact check both include it (it matters with optimize_damping only).
    double velocity_filter_hz = 0.0;
    IdentificationOptions identification;

    /// Throws std::invalid_argument naming the option, the value and the allowed range.
    void validate() const;
};

/// Values autotune writes are rounded to this many significant digits (to nearest; k_c
/// down if nearest would pass the bound itself), and everything downstream of the rounding (the
/// sizing, both checks) uses the rounded values: the file reads `mass = 0.100123`, not
/// 17 digits of false precision, and `haptic-tune size --config` reproduces its bound.
/// 1e-6 relative is far below the identification's standard errors (1e-3 and up).
inline constexpr int kAutotuneSignificantDigits = 6;

/// `value` to `digits` significant digits: to nearest, or towards zero when `down`.
double round_significant(double value, int digits, bool down = false);

/// One axis: what was identified, its own bound, and the chosen coupling held against it.
struct AutotuneAxis {
    IdentifiedAxis identified;
    /// The identified m and b rounded to kAutotuneSignificantDigits: what is sized and
    /// checked (and, for the binding axis, written).
    theory::DeviceModel device;
    /// The `encoder` bound for this axis alone (b_c = 0, or the optimised pair).
    ImpedanceSizing bound;
    /// Standard error of bound.coupling.stiffness_n_per_m, N/m: the identification's
    /// standard errors of m and b (with their correlation) propagated through the sizing by
    /// central differences.
    double bound_stiffness_std_error_n_per_m = 0.0;
    /// The chosen coupling (AutotuneResult::coupling) on this axis's device, exact model.
    ExactCheck exact;
};

struct AutotuneResult {
    std::vector<AutotuneAxis> axes;
    int binding_axis = 0;  ///< index into axes: the smallest bound stiffness
    /// The binding axis's (rounded) device: what [device.model] should say, so that the
    /// daemon's start-up check re-checks the binding case.
    theory::DeviceModel device;
    theory::SpringDamperCoupling bound;  ///< the binding axis's passive bound
    /// (margin x bound k_c, bound b_c), rounded: what to write.
    theory::SpringDamperCoupling coupling;
    double margin = 0.0;
    double rate_hz = 0.0;
    double delay_periods = 0.0;  ///< the loop delay sized and checked for
    bool optimize_damping = false;

    /// The exact model finds `coupling` stable on every axis. When false, do not write it.
    bool verified = false;
    int worst_axis = 0;  ///< the axis whose exact check has the largest spectral radius
    /// One sentence: what the exact model found (the worst axis, operator, environment,
    /// spectral radius and frequency), and, when not verified, what to do.
    std::string verdict;
    /// Things a user should know that do not stop the result, e.g. a margin smaller than
    /// three standard errors of the bound, or a fit that stopped before its tolerances.
    std::vector<std::string> warnings;
    double solve_time_s = 0.0;  ///< wall time: identification, sizing and the exact checks

    const AutotuneAxis& binding() const { return axes.at(static_cast<std::size_t>(binding_axis)); }
};

/// The whole pipeline on a log. Throws std::invalid_argument for bad options,
/// IdentificationRefused when some axis cannot be identified (identify_all_axes) and
/// InfeasibleCoupling if sizing finds no coupling. A coupling the exact model rejects is
/// not an exception: the result says verified = false and why.
AutotuneResult autotune(const TelemetryLog& log, const AutotuneOptions& options);

/// Steps 2-4 on axes identified already (for tests, and for a caller that identified them
/// itself). `axes` must not be empty.
AutotuneResult autotune(std::vector<IdentifiedAxis> axes, const AutotuneOptions& options);

}  // namespace hapticd::tune
