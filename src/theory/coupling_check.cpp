#include "hapticd/theory/coupling_check.hpp"

#include <cmath>
#include <vector>

#include "hapticd/theory/frequency_grid.hpp"

namespace hapticd::theory {

CouplingCheck check_coupling(const DeviceModel& device, const SpringDamperCoupling& coupling,
                             const LoopModel& model, double rate_hz, int grid_points) {
    const double period = 1.0 / rate_hz;
    const auto margin = [&](double theta) {
        return coupling_margin(device, coupling, model, theta, period);
    };
    const std::vector<double> grid = frequency_grid(grid_points);
    std::vector<double> margins = conductance_bounds(model, device.damping_n_s_per_m, grid);
    for (std::size_t i = 0; i < grid.size(); ++i) {
        margins[i] = relative_margin(coupling_conductance(coupling, grid[i], period), margins[i]);
    }
    const GridMinimum interior = minimize_tabulated(margin, grid, margins);
    const double dc = coupling_margin_at_dc(device, coupling, model, period);
    CouplingCheck result;
    // A margin flat in frequency (the passive model at b_c = 0 binds everywhere) is
    // reported at its low-frequency end: within rounding, the limit f -> 0 counts as worst.
    if (dc <= interior.value + 1e-9 * std::abs(dc)) {
        result.worst_margin = dc;
        result.worst_frequency_hz = 0.0;
    } else {
        result.worst_margin = interior.value;
        result.worst_frequency_hz = frequency_hz(interior.theta, period);
    }
    // (19): Re Z_dI = b > 0 and Re(1/Z_cI) = R/(R²+X²) >= 0 for non-negative gains (with a
    // velocity filter too: Re B > 0, velocity_filter.hpp); (20)-(21) is the margin.
    result.unconditionally_stable = device.damping_n_s_per_m > 0.0 && result.worst_margin >= 0.0;
    return result;
}

}  // namespace hapticd::theory
