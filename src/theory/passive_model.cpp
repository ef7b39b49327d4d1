#include "hapticd/theory/passive_model.hpp"

#include <algorithm>

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

double worst_boundary_angle(double theta, double whole_periods, double fraction) {
    // h(χ) vanishes at χ = ±π/2 and is smooth between; 48 samples bracket its maximum, and a
    // golden-section search refines it. tests/theory/passive_model_test.cpp holds the result
    // against a brute-force maximum over 20000 points for delays up to 9.9 periods.
    constexpr int kScan = 48;
    constexpr double kHalfPi = std::numbers::pi / 2.0;
    const auto h = [&](double chi) { return boundary_lambda(theta, chi, whole_periods, fraction); };
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
    double lo = -kHalfPi + (best - 1) * step;
    double hi = -kHalfPi + (best + 1) * step;
    const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
    double x1 = hi - inv_phi * (hi - lo);
    double x2 = lo + inv_phi * (hi - lo);
    double f1 = h(x1);
    double f2 = h(x2);
    for (int i = 0; i < 60 && hi - lo > 1e-10; ++i) {
        if (f1 > f2) {
            hi = x2, x2 = x1, f2 = f1, x1 = hi - inv_phi * (hi - lo), f1 = h(x1);
        } else {
            lo = x1, x1 = x2, f1 = f2, x2 = lo + inv_phi * (hi - lo), f2 = h(x2);
        }
    }
    return f1 > f2 ? x1 : x2;
}

}  // namespace passive_detail

double passive_delay_samples(double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    const double a = 1.0 + d.whole_periods + d.fraction;
    return std::sqrt(a * a + d.fraction * (1.0 - d.fraction));
}

}  // namespace hapticd::theory
