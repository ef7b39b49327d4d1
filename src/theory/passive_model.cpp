#include "hapticd/theory/passive_model.hpp"

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

Complex passive_alias_weight_sum(double theta, double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    const Complex rho = (1.0 - d.fraction) + d.fraction * std::polar(1.0, -theta);
    return std::polar(1.0, -(1.0 + d.whole_periods) * theta) * rho;
}

double passive_delay_samples(double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    const double a = 1.0 + d.whole_periods + d.fraction;
    return std::sqrt(a * a + d.fraction * (1.0 - d.fraction));
}

}  // namespace hapticd::theory
