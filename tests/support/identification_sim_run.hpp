// Simulated identification runs for the tests and benchmarks of `haptic-tune identify`:
// the sim device (lockstep clock, exact ZOH, 10 µm encoder counts, Coulomb friction) driven
// open loop by a Schroeder-phased multisine, logged through the daemon's own telemetry CSV
// writer (servo/telemetry_csv.hpp).
//
// The force the sim applies is the logged command plus a constant offset and white force
// noise (one Gaussian draw per period, seeded): what an amplifier with an offset and noise
// does to the command the daemon logs. So the truth of the model
//     m dv/dt + b v = F - F_c sign(v) + F_0
// is (mass_kg, damping_n_s_per_m, coulomb_n, offset_n), with F the logged f{i}_n.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hapticd/servo/telemetry.hpp"
#include "hapticd/tune/telemetry_log.hpp"

namespace hapticd::tune::testing {

struct SimulatedRun {
    // The device: the pen display of config/devices/pen-display.toml, with friction.
    double mass_kg = 0.1;
    double damping_n_s_per_m = 2.0;
    double coulomb_n = 0.2;
    double offset_n = 0.05;
    double counts_per_meter = 1e5;  ///< 10 µm counts
    double force_limit_n = 20.0;
    double rate_hz = 1000.0;
    double delay_s = 0.0;  ///< [device.sim] delay: from a sample to its command acting
    int axes = 1;
    // The run.
    double duration_s = 10.0;
    double force_rms_n = 1.0;     ///< RMS of the multisine command
    double low_hz = 1.0;          ///< lowest line
    double high_hz = 50.0;        ///< highest line
    int lines = 24;               ///< log-spaced lines (on a 0.1 Hz grid) between them
    double force_noise_n = 0.02;  ///< standard deviation of the applied force's noise, N
    double command_bias_n = 0.0;  ///< a constant added to the command (logged with it)
    double clip_fraction = 1.0;   ///< the command is clipped at this fraction of its peak
    std::uint64_t seed = 1;
};

/// A Schroeder-phased multisine: `lines` log-spaced frequencies between low and high
/// (rounded to a 0.1 Hz grid, so periodic in 10 s; duplicates dropped), equal amplitudes,
/// Schroeder's phases (generalised to unevenly spaced lines) for a low crest factor, scaled
/// to `rms_n`; `samples` values at `rate_hz`.
/// `delay_s` shifts it in time (a different signal per axis).
std::vector<double> schroeder_multisine(double rms_n, double low_hz, double high_hz, int lines,
                                        double rate_hz, std::size_t samples, double delay_s = 0.0);

/// Runs the sim open loop; one record per tick, as the daemon's loop would log it
/// (x = counts / counts_per_meter, v by backward difference, f the command).
std::vector<servo::TelemetryRecord> simulate_run(const SimulatedRun& run);

/// The records as the daemon's telemetry CSV (header and lines from telemetry_csv.hpp).
std::string daemon_csv(const std::vector<servo::TelemetryRecord>& records, int axes);

/// simulate_run, written by the daemon's writer and read back by read_telemetry_log's parser.
TelemetryLog simulated_log(const SimulatedRun& run);

}  // namespace hapticd::tune::testing
