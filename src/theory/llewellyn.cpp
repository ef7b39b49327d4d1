#include "hapticd/theory/llewellyn.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "hapticd/theory/frequency_grid.hpp"

namespace hapticd::theory {

PassivityResult passivity(const TwoPort& network) {
    // Hermitian part [[a, c], [conj(c), d]] with a = Re p11, d = Re p22,
    // c = (p12 + conj(p21))/2; its smallest eigenvalue decides (6).
    const double a = network.p11.real();
    const double d = network.p22.real();
    const double c = std::abs((network.p12 + std::conj(network.p21)) / 2.0);
    const double mean = (a + d) / 2.0;
    const double radius = std::hypot((a - d) / 2.0, c);
    const double min_eigenvalue = mean - radius;
    // (7): a >= 0, d >= 0, a d - |c|^2 >= 0; identical to min_eigenvalue >= 0.
    const bool passive = a >= 0.0 && d >= 0.0 && a * d - c * c >= 0.0;
    return {passive, min_eigenvalue};
}

LlewellynResult llewellyn(const TwoPort& network) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    LlewellynResult r;
    r.re_p11 = network.p11.real();
    r.re_p22 = network.p22.real();
    const Complex loop = network.p12 * network.p21;
    const double lhs = 2.0 * r.re_p11 * r.re_p22;     // (8), left side
    const double rhs = std::abs(loop) + loop.real();  // (8), right side, >= 0
    r.stability_factor = std::abs(loop) > 0.0 ? (lhs - loop.real()) / std::abs(loop) : kInf;
    r.margin = rhs > 0.0 ? lhs / rhs - 1.0 : (lhs >= 0.0 ? kInf : -kInf);
    r.unconditionally_stable = r.re_p11 >= 0.0 && r.re_p22 >= 0.0 && lhs >= rhs;
    return r;
}

LlewellynSweep llewellyn_over_frequency(const std::function<TwoPort(double)>& network_at,
                                        double rate_hz, int grid_points) {
    const std::vector<double> grid = frequency_grid(grid_points);
    const GridMinimum worst =
        minimize_on_grid([&](double theta) { return llewellyn(network_at(theta)).margin; }, grid);
    LlewellynSweep sweep;
    sweep.worst_margin = worst.value;
    sweep.worst_frequency_hz = frequency_hz(worst.theta, 1.0 / rate_hz);
    sweep.worst_re_p11 = std::numeric_limits<double>::infinity();
    bool all_hold = true;
    for (double theta : grid) {
        const LlewellynResult r = llewellyn(network_at(theta));
        sweep.worst_re_p11 = std::min(sweep.worst_re_p11, r.re_p11);
        all_hold = all_hold && r.unconditionally_stable;
    }
    sweep.unconditionally_stable = all_hold && worst.value >= 0.0;
    return sweep;
}

}  // namespace hapticd::theory
