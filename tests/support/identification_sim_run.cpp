#include "identification_sim_run.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include "hapticd/device/sim/sim_device.hpp"
#include "hapticd/servo/telemetry_csv.hpp"

namespace hapticd::tune::testing {

std::vector<double> schroeder_multisine(double rms_n, double low_hz, double high_hz, int lines,
                                        double rate_hz, std::size_t samples, double delay_s) {
    constexpr double kGridHz = 0.1;
    std::vector<double> frequencies;
    for (int k = 0; k < lines; ++k) {
        const double ratio = lines > 1 ? static_cast<double>(k) / (lines - 1) : 0.0;
        const double f = kGridHz * std::round(low_hz * std::pow(high_hz / low_hz, ratio) / kGridHz);
        if (frequencies.empty() || f > frequencies.back()) frequencies.push_back(f);
    }
    const double count = static_cast<double>(frequencies.size());
    const double amplitude = rms_n * std::sqrt(2.0 / count);
    std::vector<double> signal(samples, 0.0);
    // Schroeder's phases make the sum sweep its lines like a chirp that spends an equal share
    // of the period P = 1/grid on each: line k is delayed by t_k = P k/K, and dφ/df = -2π t
    // gives φ_k = φ_{k-1} - 2π (f_k - f_{k-1}) P k/K (-π k(k+1)/K for consecutive harmonics).
    double phase = 0.0;
    for (std::size_t k = 0; k < frequencies.size(); ++k) {
        const double step_hz = frequencies[k] - (k == 0 ? 0.0 : frequencies[k - 1]);
        phase -= 2.0 * std::numbers::pi * step_hz / kGridHz * static_cast<double>(k + 1) / count;
        const double omega = 2.0 * std::numbers::pi * frequencies[k];
        for (std::size_t n = 0; n < samples; ++n) {
            const double t = static_cast<double>(n) / rate_hz + delay_s;
            signal[n] += amplitude * std::cos(omega * t + phase);
        }
    }
    return signal;
}

std::vector<servo::TelemetryRecord> simulate_run(const SimulatedRun& run) {
    device::sim::SimConfig config;
    config.axes = run.axes;
    config.rate_hz = run.rate_hz;
    config.mass_kg = run.mass_kg;
    config.damping_n_s_per_m = run.damping_n_s_per_m;
    config.counts_per_meter = run.counts_per_meter;
    config.force_limit_n = run.force_limit_n;
    config.coulomb_n = run.coulomb_n;
    config.delay_s = run.delay_s;
    config.clock = device::sim::SimClock::lockstep;
    device::sim::SimDevice sim;
    sim.open(config);

    const auto samples = static_cast<std::size_t>(std::llround(run.duration_s * run.rate_hz)) + 1;
    std::vector<std::vector<double>> command(static_cast<std::size_t>(run.axes));
    for (int axis = 0; axis < run.axes; ++axis) {
        command[axis] = schroeder_multisine(run.force_rms_n, run.low_hz, run.high_hz, run.lines,
                                            run.rate_hz, samples, 0.37 * axis);
        double peak = 0.0;
        for (double f : command[axis]) peak = std::max(peak, std::abs(f));
        const double clip = run.clip_fraction * peak;
        for (double& f : command[axis]) f = std::clamp(f, -clip, clip) + run.command_bias_n;
    }
    std::mt19937_64 random(run.seed);
    std::normal_distribution<double> noise(0.0, 1.0);

    std::vector<servo::TelemetryRecord> records(samples);
    std::array<double, servo::kMaxAxes> previous_x{};
    for (std::size_t n = 0; n < samples; ++n) {
        servo::Sample sample;
        sim.read(sample);
        servo::TelemetryRecord& r = records[n];
        r.tick = n;
        r.t_s = static_cast<double>(n) / run.rate_hz;
        r.status = sample.status;
        servo::Command out;
        out.enable = true;
        for (int axis = 0; axis < run.axes; ++axis) {
            const double x =
                static_cast<double>(sample.encoder_counts[axis]) / run.counts_per_meter;
            r.x_m[axis] = x;
            r.v_mps[axis] = n == 0 ? 0.0 : (x - previous_x[axis]) * run.rate_hz;
            r.xe_m[axis] = x;
            r.f_n[axis] = command[axis][n];
            previous_x[axis] = x;
            out.force_n[axis] = command[axis][n] + run.offset_n + run.force_noise_n * noise(random);
        }
        sim.write(out);
    }
    sim.close();
    return records;
}

std::string daemon_csv(const std::vector<servo::TelemetryRecord>& records, int axes) {
    std::ostringstream out;
    servo::write_csv_header(out, axes);
    for (const servo::TelemetryRecord& r : records) servo::write_csv_record(out, r, axes);
    return out.str();
}

TelemetryLog simulated_log(const SimulatedRun& run) {
    std::istringstream in(daemon_csv(simulate_run(run), run.axes));
    return parse_telemetry_log(in, "simulated.csv");
}

}  // namespace hapticd::tune::testing
