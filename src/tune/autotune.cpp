#include "hapticd/tune/autotune.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hapticd/input/range.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tune {
namespace {

using Clock = std::chrono::steady_clock;

ImpedanceSizingRequest sizing_request(const theory::DeviceModel& device,
                                      const AutotuneOptions& options) {
    ImpedanceSizingRequest request;
    request.device = device;
    request.rate_hz = options.rate_hz;
    request.model = {theory::HoldModel::passive, options.delay_periods};
    request.velocity_filter_hz = options.velocity_filter_hz;
    request.coupling_damping_n_s_per_m =
        options.optimize_damping ? std::nullopt : std::optional<double>(0.0);
    return request;
}

double bound_stiffness(const theory::DeviceModel& device, const AutotuneOptions& options) {
    return size_impedance_coupling(sizing_request(device, options)).coupling.stiffness_n_per_m;
}

/// Standard error of the bound stiffness from those of m and b: first-order propagation,
/// the partial derivatives by central differences of the sizing itself (the bound is
/// smooth in m and b: 2b/T at b_c = 0, a saddle value with the optimised damping).
double bound_std_error(const IdentifiedAxis& axis, const AutotuneOptions& options) {
    const theory::DeviceModel device = axis.device();
    constexpr double kRelativeStep = 1e-4;
    const double dm = device.mass_kg * kRelativeStep;
    const double db = device.damping_n_s_per_m * kRelativeStep;
    const auto with = [&](double mass, double damping) {
        return bound_stiffness({mass, damping}, options);
    };
    const double d_mass = (with(device.mass_kg + dm, device.damping_n_s_per_m) -
                           with(device.mass_kg - dm, device.damping_n_s_per_m)) /
                          (2.0 * dm);
    const double d_damping = (with(device.mass_kg, device.damping_n_s_per_m + db) -
                              with(device.mass_kg, device.damping_n_s_per_m - db)) /
                             (2.0 * db);
    const double from_mass = d_mass * axis.std_error.mass_kg;
    const double from_damping = d_damping * axis.std_error.damping_n_s_per_m;
    // The correlation is that of log m and log b, which to first order is that of m and b.
    const double rho = axis.correlation[0][1];
    const double variance = from_mass * from_mass + from_damping * from_damping +
                            2.0 * (std::isfinite(rho) ? rho : 0.0) * from_mass * from_damping;
    return std::sqrt(std::max(variance, 0.0));
}

std::string percent(double fraction) {
    std::ostringstream out;
    out.precision(2);
    out << std::fixed << 100.0 * fraction << " %";
    return out.str();
}

theory::DeviceModel rounded(const theory::DeviceModel& device) {
    return {round_significant(device.mass_kg, kAutotuneSignificantDigits),
            round_significant(device.damping_n_s_per_m, kAutotuneSignificantDigits)};
}

}  // namespace

double round_significant(double value, int digits, bool down) {
    if (value == 0.0 || !std::isfinite(value)) return value;
    // value = q 10^e with q an integer of `digits` digits. q and 10^|e| (|e| <= 22) are exact
    // doubles, so q * 10^e or q / 10^-e is the double nearest the decimal, which is what
    // the config editor's shortest round-trip form then prints.
    const int exponent = static_cast<int>(std::floor(std::log10(std::abs(value)))) - digits + 1;
    const double power = std::pow(10.0, std::abs(exponent));
    const double scaled = exponent >= 0 ? value / power : value * power;
    const double q = down ? std::trunc(scaled) : std::round(scaled);
    return exponent >= 0 ? q * power : q / power;
}

void AutotuneOptions::validate() const {
    check_rate(rate_hz);
    if (!(margin > 0.0 && margin <= 1.0)) {
        input::reject_out_of_range(
            "margin", margin,
            "(0, 1] (the fraction of the largest stable coupling stiffness to use)");
    }
    check_delay_periods(delay_periods);
    check_velocity_filter(velocity_filter_hz, rate_hz);
    identification.validate();
}

AutotuneResult autotune(const TelemetryLog& log, const AutotuneOptions& options) {
    options.validate();
    const Clock::time_point start = Clock::now();
    AutotuneResult result = autotune(identify_all_axes(log, options.identification), options);
    result.solve_time_s = std::chrono::duration<double>(Clock::now() - start).count();
    return result;
}

AutotuneResult autotune(std::vector<IdentifiedAxis> axes, const AutotuneOptions& options) {
    options.validate();
    if (axes.empty()) throw std::invalid_argument("autotune: no identified axis");
    const Clock::time_point start = Clock::now();

    AutotuneResult result;
    result.margin = options.margin;
    result.rate_hz = options.rate_hz;
    result.delay_periods = options.delay_periods;
    result.optimize_damping = options.optimize_damping;
    result.axes.reserve(axes.size());
    for (IdentifiedAxis& identified : axes) {
        AutotuneAxis axis;
        axis.device = rounded(identified.device());
        axis.bound = size_impedance_coupling(sizing_request(axis.device, options));
        axis.bound_stiffness_std_error_n_per_m = bound_std_error(identified, options);
        axis.identified = std::move(identified);
        result.axes.push_back(std::move(axis));
    }

    // The binding axis: the smallest bound stiffness. At b_c = 0 the feasible stiffnesses
    // of each axis form an interval [0, bound] (docs/sizing.md), so a stiffness below the
    // smallest bound satisfies every axis's (21); with the optimised damping the exact
    // checks below are what guarantees the other axes.
    for (std::size_t i = 1; i < result.axes.size(); ++i) {
        if (result.axes[i].bound.coupling.stiffness_n_per_m <
            result.binding().bound.coupling.stiffness_n_per_m) {
            result.binding_axis = static_cast<int>(i);
        }
    }
    const AutotuneAxis& binding = result.binding();
    result.device = binding.device;
    result.bound = binding.bound.coupling;
    // k_c to nearest, but never above the bound (margin 1).
    double stiffness = round_significant(options.margin * result.bound.stiffness_n_per_m,
                                         kAutotuneSignificantDigits);
    if (stiffness > result.bound.stiffness_n_per_m) {
        stiffness = round_significant(result.bound.stiffness_n_per_m, kAutotuneSignificantDigits,
                                      /*down=*/true);
    }
    result.coupling = {
        stiffness, round_significant(result.bound.damping_n_s_per_m, kAutotuneSignificantDigits),
        options.velocity_filter_hz};

    for (std::size_t i = 0; i < result.axes.size(); ++i) {
        AutotuneAxis& axis = result.axes[i];
        axis.exact =
            check_exact(axis.device, result.coupling, options.rate_hz, options.delay_periods);
        if (axis.exact.worst_spectral_radius >
            result.axes[static_cast<std::size_t>(result.worst_axis)].exact.worst_spectral_radius) {
            result.worst_axis = static_cast<int>(i);
        }
        const IdentifiedAxis& id = axis.identified;
        if (!id.report.converged) {
            result.warnings.push_back("axis " + std::to_string(id.axis) +
                                      ": the identification stopped before Ceres' tolerances "
                                      "were met (" +
                                      id.report.termination + "); check its residual");
        }
        // The margin should cover the bound's uncertainty: three standard errors.
        const double bound_k = axis.bound.coupling.stiffness_n_per_m;
        const double relative_error = axis.bound_stiffness_std_error_n_per_m / bound_k;
        if (result.coupling.stiffness_n_per_m > bound_k * (1.0 - 3.0 * relative_error)) {
            result.warnings.push_back(
                "axis " + std::to_string(id.axis) + ": the coupling stiffness is " +
                percent(result.coupling.stiffness_n_per_m / bound_k) +
                " of this axis's bound, and the bound's standard error is " +
                percent(relative_error) +
                " of it: the margin leaves less than three standard errors (a longer or "
                "stronger excitation run narrows them; a smaller margin covers them)");
        }
    }
    bool stable = true;
    for (const AutotuneAxis& axis : result.axes) stable = stable && axis.exact.stable;
    result.verified = stable;

    const AutotuneAxis& worst = result.axes[static_cast<std::size_t>(result.worst_axis)];
    std::ostringstream verdict;
    verdict.precision(6);
    if (stable) {
        // 1 - |z| is tiny for any stable design (a lightly damped operator mode sets it,
        // exact_model.hpp): it names the case, it is not a distance to instability.
        verdict << "the exact model finds the coupling stable on every axis ("
                << worst.exact.cases_checked << " operator x environment cases each); the "
                << "slowest-decaying case, 1 - |z| = " << worst.exact.worst_margin
                << " per tick at " << worst.exact.worst_frequency_hz << " Hz on axis "
                << worst.identified.axis << ", is " << worst.exact.worst_operator.describe()
                << " against " << worst.exact.worst_environment.describe();
    } else {
        verdict << "the exact model finds the coupling unstable on axis " << worst.identified.axis
                << ": " << worst.exact.worst_operator.describe() << " against "
                << worst.exact.worst_environment.describe()
                << " grows by |z| = " << worst.exact.worst_spectral_radius << " per tick at "
                << worst.exact.worst_frequency_hz << " Hz";
        verdict << "; try a smaller margin";
    }
    result.verdict = verdict.str();
    result.solve_time_s = std::chrono::duration<double>(Clock::now() - start).count();
    return result;
}

}  // namespace hapticd::tune
