// Unconditional stability of the impedance display with a spring-damper coupling, (19)-(21),
// checked at every frequency up to Nyquist.
#pragma once

#include "hapticd/theory/benchmark.hpp"

namespace hapticd::theory {

struct CouplingCheck {
    bool unconditionally_stable = false;
    /// Smallest relative margin of (21) over 0 < f <= Nyquist (coupling_margin).
    double worst_margin = 0.0;
    /// Where it occurs, in hertz; 0 when the binding point is the limit f -> 0.
    double worst_frequency_hz = 0.0;
};

/// Checks (19)-(21) for the device at `rate_hz` on a dense grid (with the f -> 0 limit),
/// refining the worst point. `grid_points` trades speed for resolution.
CouplingCheck check_coupling(const DeviceModel& device, const SpringDamperCoupling& coupling,
                             const LoopModel& model, double rate_hz, int grid_points = 4096);

}  // namespace hapticd::theory
