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

/// Newton's method on φ (ShiftedHoldSlope) near `start`. nullopt when a step leaves
/// start ± `reach`, φ' is not negative (not a maximum), or it has not converged to
/// `tolerance` in 12 steps.
std::optional<double> newton_maximum(const ShiftedHold<double>& h, double start, double reach,
                                     double tolerance) {
    const ShiftedHoldSlope slope(h);
    double x = start;
    for (int i = 0; i < 12; ++i) {
        const auto [phi, dphi] = slope(x);
        if (!(dphi < 0.0)) return std::nullopt;
        const double step = phi / dphi;
        x -= step;
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
    // Warm start: the maximiser extrapolated linearly in θ from the previous two, then Newton
    // steps on h' (analytic, ShiftedHoldSlope) while they stay within ±0.02 rad of it on a
    // maximum; otherwise, the full search.
    constexpr double kBracket = 0.02;
    std::size_t known = 0;  // maximisers found so far (the extrapolation needs two)
    double chi1 = 0.0, chi2 = 0.0, theta1 = 0.0, theta2 = 0.0;  // the last two
    for (double theta : thetas) {
        const passive_detail::ShiftedHold<double> h(theta, d.whole_periods, d.fraction);
        std::optional<double> chi;
        if (known > 0) {
            const double start =
                known > 1 ? chi1 + (chi1 - chi2) * (theta - theta1) / (theta1 - theta2) : chi1;
            chi = passive_detail::newton_maximum(h, start, kBracket,
                                                 passive_detail::angle_tolerance(theta));
        }
        if (!chi) chi = passive_detail::worst_boundary_angle(theta, d.whole_periods, d.fraction);
        out.push_back(h(*chi));
        chi2 = chi1, theta2 = theta1;
        chi1 = *chi, theta1 = theta;
        ++known;
    }
    return out;
}

double passive_delay_samples(double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    const double a = 1.0 + d.whole_periods + d.fraction;
    return std::sqrt(a * a + d.fraction * (1.0 - d.fraction));
}

}  // namespace hapticd::theory
