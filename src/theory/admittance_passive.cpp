#include "hapticd/theory/admittance_passive.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "hapticd/theory/passive_model.hpp"

namespace hapticd::theory {

double velocity_loop_damping_needed(const PiVelocityLoop& loop, double theta,
                                    double sample_period_s, double delay_periods) {
    return port_damping_needed(pi_gain(loop, theta, sample_period_s), theta, delay_periods);
}

double velocity_loop_damping_bound(const PiVelocityLoop& loop, double sample_period_s,
                                   double delay_periods) {
    const LoopDelay d = split_delay(delay_periods);
    if (d.whole_periods == 0 && d.fraction == 0.0) {
        // Re ζ = -k_p cos θ + k_i T/2 (Re(-e^{-jθ}/(1 - e^{-jθ})) = 1/2): largest at Nyquist.
        return loop.proportional_gain_n_s_per_m +
               loop.integral_gain_n_per_m * sample_period_s / 2.0;
    }
    constexpr int kPoints = 4096;
    double worst = 0.0;
    for (int i = 1; i <= kPoints; ++i) {
        const double theta = std::numbers::pi * i / kPoints;
        worst = std::max(worst,
                         velocity_loop_damping_needed(loop, theta, sample_period_s, delay_periods));
    }
    return worst;
}

AliasReach free_space_alias_reach(const DeviceModel& device, const PiVelocityLoop& loop,
                                  const MassDamperCoupling& coupling, double theta,
                                  double sample_period_s, int whole_periods) {
    const double t = sample_period_s;
    const double m = device.mass_kg, b = device.damping_n_s_per_m;
    const Complex z_inv = std::polar(1.0, -theta);
    const Complex delay = std::polar(1.0, -whole_periods * theta);
    const Complex k_pi = pi_gain(loop, theta, t);
    const Complex y_v = coupling_admittance(coupling, theta, t);  // free space: Y_v = Y_cA
    const Complex g = k_pi * y_v * delay;
    const Complex c_h = (1.0 + z_inv) / 2.0;  // μ = 0
    const Complex r = 1.0 + g * c_h;
    const Complex beta_inf = g * (1.0 - z_inv) * (m / t);
    const Complex direction = beta_inf / std::abs(beta_inf);
    const double half_sine = std::sin(theta / 2.0);
    // δ = Σ_k (|β_k| - Re(conj(β̂_∞) β_k)): its terms fall like 1/k², so 2·10^4 + 1 of them
    // leave a relative 1e-4 of it. A resonant alias (u_k = 1/b) moves Σ β_k u_k by
    // Re(conj(β̂_∞) β_k)/b along β̂_∞; the fewest that reach R take the largest first.
    constexpr int kTerms = 10000;
    double defect = 0.0;
    std::vector<double> along_each;
    along_each.reserve(2 * kTerms + 1);
    for (int k = -kTerms; k <= kTerms; ++k) {
        const double theta_k = theta + 2.0 * std::numbers::pi * k;
        const double s_k = 4.0 * half_sine * half_sine / (theta_k * theta_k);
        const Complex beta =
            k_pi * delay *
            (y_v * (1.0 - z_inv) * (m / t + b / Complex(0.0, theta_k)) - z_inv * s_k);
        const double projection = (std::conj(direction) * beta).real();
        defect += std::abs(beta) - projection;
        along_each.push_back(projection);
    }
    const double along = (std::conj(direction) * r).real();
    AliasReach out;
    out.reach = along + defect / (2.0 * b);
    if (along > 0.0) {
        // The largest first, off a heap: the count is small next to the terms.
        std::make_heap(along_each.begin(), along_each.end());
        double sum = 0.0;
        std::size_t n = 0;
        for (auto end = along_each.end(); end != along_each.begin() && sum < b * along; --end) {
            std::pop_heap(along_each.begin(), end);
            sum += *(end - 1);
            ++n;
        }
        out.resonant_aliases_needed = static_cast<double>(n);
    }
    return out;
}

}  // namespace hapticd::theory
