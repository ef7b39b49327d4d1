#include "hapticd/theory/passive_model.hpp"

#include <algorithm>
#include <optional>

namespace hapticd::theory {

LoopDelay split_delay(double delay_periods) {
    const double whole = std::floor(delay_periods);
    return {static_cast<int>(whole), delay_periods - whole};
}

double port_damping_needed(Complex controller_impedance, double theta, double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    const Complex zeta = -controller_impedance * std::polar(1.0, -(1.0 + d.whole_periods) * theta);
    const Complex rho = (1.0 - d.fraction) + d.fraction * std::polar(1.0, -theta);
    const double re = (zeta * rho).real();
    // 1 - |ρ|² = 2φ(1 - φ)(1 - cos θ), kept exact as θ -> 0.
    const double half_sine = std::sin(theta / 2.0);
    const double leak = 4.0 * d.fraction * (1.0 - d.fraction) * half_sine * half_sine;
    return 0.5 * (re + std::sqrt(re * re + std::norm(zeta) * leak));
}

namespace passive_detail {

namespace {

/// Golden-section search for the maximum of h on [lo, hi] to `tolerance` rad.
template <typename F>
double golden_maximum(const F& h, double lo, double hi, double tolerance) {
    const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
    double x1 = hi - inv_phi * (hi - lo);
    double x2 = lo + inv_phi * (hi - lo);
    double f1 = h(x1);
    double f2 = h(x2);
    while (hi - lo > tolerance) {
        if (f1 > f2) {
            hi = x2, x2 = x1, f2 = f1, x1 = hi - inv_phi * (hi - lo), f1 = h(x1);
        } else {
            lo = x1, x1 = x2, f1 = f2, x2 = lo + inv_phi * (hi - lo), f2 = h(x2);
        }
    }
    return f1 > f2 ? x1 : x2;
}

/// The maximum's width in χ shrinks with θ (it sits within about θ of -π/2 as θ -> 0), so
/// the search resolves χ to a millionth of min(θ, 1).
double angle_tolerance(double theta) { return 1e-6 * std::min(theta, 1.0); }

/// Newton's method for a maximum of h near `start`: the root of h' with h' and h'' by central
/// differences at 1e3 x the tolerance. nullopt when a step leaves start ± `reach`, h is not
/// concave, or it has not converged to `tolerance` in 12 steps.
template <typename F>
std::optional<double> newton_maximum(const F& h, double start, double reach, double tolerance) {
    const double e = 1e3 * tolerance;
    double x = start;
    for (int i = 0; i < 12; ++i) {
        const double lo = h(x - e), mid = h(x), hi = h(x + e);
        const double curvature = (hi - 2.0 * mid + lo) / (e * e);
        if (!(curvature < 0.0)) return std::nullopt;
        const double step = -(hi - lo) / (2.0 * e) / curvature;
        x += step;
        if (!(std::abs(x - start) <= reach)) return std::nullopt;
        if (std::abs(step) <= tolerance) return x;
    }
    return std::nullopt;
}

}  // namespace

double worst_boundary_angle(double theta, double whole_periods, double fraction) {
    // h(χ) vanishes at χ = ±π/2 and is smooth between; 24 samples bracket its maximum, and a
    // golden-section search to 1e-6 min(θ, 1) rad refines it (h is flat at its maximum, so M
    // is then exact to about 1e-12). tests/theory/passive_model_test.cpp holds the result against a
    // brute-force maximum over 200000 lossless environments for delays up to 9.9 periods.
    constexpr int kScan = 24;
    constexpr double kHalfPi = std::numbers::pi / 2.0;
    const ShiftedHold<double> h(theta, whole_periods, fraction);
    const double step = 2.0 * kHalfPi / kScan;
    int best = 1;
    double best_value = -1.0;
    for (int i = 1; i < kScan; ++i) {
        const double value = h(-kHalfPi + i * step);
        if (value > best_value) {
            best_value = value;
            best = i;
        }
    }
    return golden_maximum(h, -kHalfPi + (best - 1) * step, -kHalfPi + (best + 1) * step,
                          angle_tolerance(theta));
}

}  // namespace passive_detail

std::vector<double> passive_hold_numerators(const std::vector<double>& thetas,
                                            double delay_periods) {
    std::vector<double> out;
    out.reserve(thetas.size());
    const LoopDelay d = split_delay(delay_periods);
    if (d.fraction == 0.0) {
        for (double theta : thetas) out.push_back(passive_hold_numerator(theta, delay_periods));
        return out;
    }
    // Warm start from the previous maximiser: Newton steps on h' (central differences) while
    // they stay within ±0.02 rad of it and h is concave there; otherwise, the full search.
    constexpr double kBracket = 0.02;
    double previous = 0.0;
    bool have_previous = false;
    for (double theta : thetas) {
        const passive_detail::ShiftedHold<double> h(theta, d.whole_periods, d.fraction);
        double chi = 0.0;
        const std::optional<double> newton =
            have_previous ? passive_detail::newton_maximum(h, previous, kBracket,
                                                           passive_detail::angle_tolerance(theta))
                          : std::nullopt;
        chi = newton ? *newton
                     : passive_detail::worst_boundary_angle(theta, d.whole_periods, d.fraction);
        out.push_back(h(chi));
        previous = chi;
        have_previous = true;
    }
    return out;
}

double passive_delay_samples(double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    const double a = 1.0 + d.whole_periods + d.fraction;
    return std::sqrt(a * a + d.fraction * (1.0 - d.fraction));
}

}  // namespace hapticd::theory
