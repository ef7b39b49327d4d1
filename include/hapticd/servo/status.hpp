// The latest state of the servo loop, for a status line on another thread (ServoLoop::status(),
// published through a Seqlock every tick).
#pragma once

#include <array>
#include <cstdint>

#include "hapticd/servo/environment_port.hpp"
#include "hapticd/servo/io.hpp"
#include "hapticd/servo/servo_state.hpp"
#include "hapticd/servo/summary.hpp"

namespace hapticd::servo {

struct StatusSnapshot {
    std::uint64_t tick = 0;
    double t_s = 0.0;
    std::array<double, kMaxAxes> x_m{};
    std::array<double, kMaxAxes> xe_m{};
    std::array<double, kMaxAxes> f_n{};
    std::uint32_t faults = 0;  ///< latched Fault mask
    std::uint32_t flags = 0;   ///< TickFlag of the last tick
    std::uint64_t overruns = 0;
    std::uint64_t solver_not_converged = 0;  ///< ticks whose series solve (17) failed so far
    double energy_j = 0.0;                   ///< passivity observer
    double soft_start_scale = 0.0;
    bool armed = false;
    ServoState state = ServoState::disabled;  ///< from armed, faults and the soft start
    double stiffness_n_per_m = 0.0;           ///< the coupling's k_c in force
    double damping_n_s_per_m = 0.0;           ///< the coupling's b_c in force
    std::uint64_t read_timeouts = 0;          ///< reads that gave no sample, so far
    std::uint64_t link_recoveries = 0;        ///< link-fault latches cleared, so far
    std::uint64_t fault_resets_taken = 0;     ///< request_fault_reset()s the ticks took, so far
    /// Wake-up latency and tick compute since the start, as the summary counts them:
    /// refreshed once a second (the histograms' walk is off the tick's compute time, after
    /// its write).
    WakeLatencySummaryUs wake_latency_us{};
    TickComputeSummaryUs tick_compute_us{};
    /// The environment's port (an external world's), as its last tick left it.
    EnvironmentPortReport environment{};
};

}  // namespace hapticd::servo
