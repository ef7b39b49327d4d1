// Identifying the device (10) from a recorded run with Ceres: `haptic-tune identify`.
// The model, its solver, the robust loss, the standard errors and the refusals are
// documented in docs/identification.md; the model's exact-hold step is in
// identification_model.hpp, the log reader in telemetry_log.hpp.
//
// Per axis, m dv/dt + b v = F - F_c sign(v) + F_0, fitted by output error: the logged force
// is replayed through an exact zero-order hold and the simulated position compared with the
// logged one, over short segments whose initial states are extra parameters (so that force
// noise and unmodelled effects cannot make a long simulation drift). Huber loss on each
// sample, scaled from the encoder resolution and the residuals' robust spread; m and b
// through their logarithms (so they stay positive); F_c >= 0 (a fit that wants F_c < 0 is
// refitted with F_c = 0). Standard errors come from (JᵀJ)⁻¹ of the four parameters (the
// inverse of their Schur-reduced information), made robust to the residuals' correlation
// within a segment (a sandwich with the segments as clusters). A log that cannot pin m and b
// to 1 % (one standard error), or in which the handle mostly sticks, is refused with the
// reason.
//
// Typical use (what `haptic-tune autotune` does):
//     const TelemetryLog log = read_telemetry_log(path);           // LogFormatError
//     for (const IdentifiedAxis& fit : identify_all_axes(log)) {   // IdentificationRefused
//         size_impedance_coupling({fit.device(), fit.rate_hz, ...});
//     }
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/input/input_error.hpp"
#include "hapticd/theory/benchmark.hpp"
#include "hapticd/tune/telemetry_log.hpp"

namespace hapticd::tune {

/// Why a log cannot identify the model.
enum class RefusalReason {
    missing_column,         ///< no x{i}_m / f{i}_n for the requested axis
    too_short,              ///< fewer samples or seconds than needed
    non_uniform_time,       ///< t_s not increasing in whole periods
    faults,                 ///< latched faults or device status bits that spoil the run
    saturated,              ///< the force sat at its limit (or safety clipped it) too often
    too_little_excitation,  ///< the data cannot tell the parameters apart (see message)
    fit_failed,             ///< Ceres could not fit the model (the message says why)
};
std::string_view to_string(RefusalReason reason);

/// The log cannot identify the model; what() says why, with the numbers.
class IdentificationRefused : public input::InputError {
  public:
    IdentificationRefused(RefusalReason reason, const std::string& what)
        : InputError(what), reason_(reason) {}
    RefusalReason reason() const { return reason_; }

  private:
    RefusalReason reason_;
};

struct IdentificationOptions {
    /// Length of a shooting segment, s. Each segment's initial position and velocity are
    /// free parameters; shorter segments follow force noise better, longer ones carry more
    /// information per parameter (docs/identification.md chooses 0.02 s).
    double segment_s = 0.02;
    /// Encoder resolution, m per count. nullopt: the smallest step between logged positions
    /// (exact for the daemon's logs, which hold counts / counts_per_meter).
    std::optional<double> resolution_m;
    /// The loop delay, s, from a position's sample to the force computed from it acting on
    /// the handle (haptic-tune diag measures it): the fit shifts the logged forces by it
    /// (HoldDelay, identification_model.hpp). >= 0 and under 10 of the log's periods.
    double delay_s = 0.0;
    /// The device's force limit, N, if known: more than `max_saturated_fraction` of the
    /// samples at |f| >= it is refused as saturated.
    std::optional<double> force_limit_n;
    /// Refusal thresholds.
    double min_duration_s = 1.0;
    double max_saturated_fraction = 0.02;
    double max_masked_fraction = 0.10;  ///< rows whose position is not a fresh sample
    /// Relative standard error of m or b above which the log is refused as too little
    /// excitation (and standard error of F_c or F_0 above this fraction of the force's RMS).
    /// 1 % keeps what is accepted within the 2 % the sizing relies on, at two standard
    /// errors. +inf turns the check off (charts of where identification fails).
    double max_relative_std_error = 0.01;
    /// Fraction of the periods the fitted handle may end at rest, held by Coulomb friction.
    /// Beyond it stick-slip dominates, and force noise at each breakaway biases the
    /// output-error fit beyond its standard errors (docs/identification.md).
    double max_stuck_fraction = 0.25;
    int max_iterations = 100;

    /// Throws std::invalid_argument naming the option, the value and the allowed range.
    void validate() const;
};

/// The four parameters, in the order of `correlation`.
struct AxisParameters {
    double mass_kg = 0.0;
    double damping_n_s_per_m = 0.0;
    double coulomb_n = 0.0;
    double offset_n = 0.0;
};

/// How the result was obtained (in the spirit of ceres::Solver::Summary).
struct IdentificationReport {
    int iterations = 0;          ///< Ceres iterations, all passes
    bool converged = false;      ///< the final Ceres pass met its tolerances
    std::string termination;     ///< Ceres' termination message of the final pass
    double solve_time_s = 0.0;   ///< wall time of identify_axis(), checks included
    double huber_scale_m = 0.0;  ///< the Huber loss' scale δ of the final pass
    std::size_t parameters = 0;  ///< 4 + 2 per segment
    /// The free fit put F_c below 0 (no friction the log can see): F_c was then held at 0
    /// and the rest refitted; coulomb's standard error is the free fit's.
    bool coulomb_held_at_zero = false;
};

struct IdentifiedAxis {
    int axis = 0;
    AxisParameters estimate;
    /// Standard errors (same units), segment-clustered sandwich over (JᵀJ)⁻¹.
    AxisParameters std_error;
    /// The textbook standard errors σ² (JᵀJ)⁻¹, which assume independent residuals; they
    /// understate the uncertainty when force noise correlates the residuals (for reports).
    AxisParameters std_error_independent;
    /// Correlation of the estimates (m, b, F_c, F_0 order; m and b through their logs).
    std::array<std::array<double, 4>, 4> correlation{};

    double residual_rms_m = 0.0;       ///< RMS of simulated - logged position
    double residual_rms_counts = 0.0;  ///< the same in encoder counts (NaN: not quantised)
    double resolution_m = 0.0;         ///< encoder resolution used; 0: not quantised
    bool resolution_estimated = true;  ///< false when it came from the options
    /// Fraction of the periods after which the fitted handle is at rest, held by Coulomb
    /// friction (refused above IdentificationOptions::max_stuck_fraction).
    double stuck_fraction = 0.0;

    double delay_s = 0.0;  ///< the loop delay the fit assumed (IdentificationOptions)
    double rate_hz = 0.0;  ///< 1 / the log's period
    double duration_s = 0.0;
    std::size_t samples = 0;         ///< rows used
    std::size_t masked_samples = 0;  ///< rows whose position was excluded (stale, dropped)
    std::size_t segments = 0;
    std::size_t gaps = 0;  ///< whole periods missing from t_s (segments break there)
    IdentificationReport report;

    /// The device (10) for sizing: m and b.
    theory::DeviceModel device() const { return {estimate.mass_kg, estimate.damping_n_s_per_m}; }
};

/// Identifies axis `axis` of `log`. Throws std::invalid_argument for bad options and
/// IdentificationRefused when the log cannot identify the model.
IdentifiedAxis identify_axis(const TelemetryLog& log, int axis,
                             const IdentificationOptions& options = {});

/// Every axis of the log, in order (each refused on its own terms).
std::vector<IdentifiedAxis> identify_all_axes(const TelemetryLog& log,
                                              const IdentificationOptions& options = {});

}  // namespace hapticd::tune
