// Speed against accuracy of haptic-tune identify: identification error and solve time against
// the log's length and the excitation's amplitude, over seeds, on the tests' simulated pen
// display (identification_sim_run.hpp). Writes a JSON table for
// tools/plot/identification_chart.py and prints a summary. Not a test: it asserts nothing.
//
//   identify_sweep [--out FILE.json] [--seeds N]
//   identify_sweep --segments [--out FILE.json] [--seeds N]
//
// Every run is identified with the standard-error and stiction checks off, so that the chart
// shows the error where the default options would refuse too; each run records whether (and
// why) the defaults refuse it.
//
// --segments: the study behind the default segment length (docs/identification.md): for
// each segment length, over seeds of the 10 s run, the spread of the estimates and how well
// the reported standard errors cover the truth (RMS of z = (estimate - truth)/SE, 1 when
// calibrated), with and without force noise.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hapticd/tune/identification.hpp"
#include "identification_sim_run.hpp"

namespace {

using hapticd::tune::IdentificationOptions;
using hapticd::tune::IdentificationRefused;
using hapticd::tune::IdentifiedAxis;
namespace testing = hapticd::tune::testing;
using nlohmann::ordered_json;

const std::vector<double> kLengthsS = {1.0, 2.0, 5.0, 10.0, 20.0, 40.0};
const std::vector<double> kAmplitudesN = {0.1, 0.2, 0.5, 1.0, 2.0};  // multisine RMS

double thread_cpu_s() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double median(std::vector<double> v) {
    if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double maximum(const std::vector<double>& v) {
    return v.empty() ? std::numeric_limits<double>::quiet_NaN()
                     : *std::max_element(v.begin(), v.end());
}

ordered_json number(double value) {
    return std::isfinite(value) ? ordered_json(value) : ordered_json(nullptr);
}

bool write_json(const ordered_json& table, const std::string& out_path) {
    if (out_path.empty()) return true;
    std::ofstream out(out_path);
    if (!out) {
        std::cerr << "identify_sweep: cannot write " << out_path << '\n';
        return false;
    }
    out << table.dump(1) << '\n';
    std::cerr << "identify_sweep: wrote " << out_path << '\n';
    return true;
}

/// The segment-length study (--segments).
int segment_study(const std::string& out_path, int seeds) {
    const std::vector<double> segments_s = {0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 2.0};
    const std::vector<double> noises_n = {0.0, 0.02, 0.05};
    IdentificationOptions options;
    options.max_relative_std_error = std::numeric_limits<double>::infinity();
    ordered_json rows = ordered_json::array();
    std::printf("%8s %9s | %9s %9s %9s | %7s %7s %7s | %8s %8s\n", "noise_n", "segment_s", "sd_m_%",
                "sd_b_%", "sd_Fc_%", "z_m", "z_b", "z_Fc", "rms_cnt", "cpu_ms");
    for (double noise : noises_n) {
        for (double segment : segments_s) {
            options.segment_s = segment;
            const testing::SimulatedRun base;
            const double truth[3] = {base.mass_kg, base.damping_n_s_per_m, base.coulomb_n};
            std::vector<double> error[3], z[3], residual, cpu;
            for (int seed = 1; seed <= seeds; ++seed) {
                testing::SimulatedRun run = base;
                run.force_noise_n = noise;
                run.seed = static_cast<std::uint64_t>(seed);
                const hapticd::tune::TelemetryLog log = testing::simulated_log(run);
                const double cpu_start = thread_cpu_s();
                const IdentifiedAxis fit = hapticd::tune::identify_axis(log, 0, options);
                cpu.push_back(thread_cpu_s() - cpu_start);
                const double estimate[3] = {fit.estimate.mass_kg, fit.estimate.damping_n_s_per_m,
                                            fit.estimate.coulomb_n};
                const double se[3] = {fit.std_error.mass_kg, fit.std_error.damping_n_s_per_m,
                                      fit.std_error.coulomb_n};
                for (int p = 0; p < 3; ++p) {
                    error[p].push_back(estimate[p] / truth[p] - 1.0);
                    z[p].push_back((estimate[p] - truth[p]) / se[p]);
                }
                residual.push_back(fit.residual_rms_counts);
            }
            const auto rms = [](const std::vector<double>& v) {
                double sum = 0.0;
                for (double x : v) sum += x * x;
                return std::sqrt(sum / static_cast<double>(v.size()));
            };
            ordered_json row = {{"force_noise_n", noise},
                                {"segment_s", segment},
                                {"rms_mass_error", rms(error[0])},
                                {"rms_damping_error", rms(error[1])},
                                {"rms_coulomb_error", rms(error[2])},
                                {"rms_z_mass", rms(z[0])},
                                {"rms_z_damping", rms(z[1])},
                                {"rms_z_coulomb", rms(z[2])},
                                {"median_residual_rms_counts", median(residual)},
                                {"median_cpu_time_s", median(cpu)}};
            std::printf("%8.3f %9.3f | %9.4f %9.4f %9.4f | %7.2f %7.2f %7.2f | %8.2f %8.1f\n",
                        noise, segment, 100.0 * rms(error[0]), 100.0 * rms(error[1]),
                        100.0 * rms(error[2]), rms(z[0]), rms(z[1]), rms(z[2]), median(residual),
                        1e3 * median(cpu));
            std::fflush(stdout);
            rows.push_back(row);
        }
    }
    const ordered_json table = {{"kind", "identification-segments"},
                                {"seeds", seeds},
                                {"duration_s", testing::SimulatedRun{}.duration_s},
                                {"rows", rows}};
    return write_json(table, out_path) ? 0 : 2;
}

int sweep(int argc, char** argv) {
    std::string out_path;
    int seeds = 5;
    bool segments = false;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--out" && i + 1 < argc) {
            out_path = argv[++i];
        } else if (arg == "--seeds" && i + 1 < argc) {
            seeds = std::atoi(argv[++i]);
        } else if (arg == "--segments") {
            segments = true;
        } else {
            std::cerr << "usage: identify_sweep [--segments] [--out FILE.json] [--seeds N]\n";
            return 2;
        }
    }
    if (seeds < 1) {
        std::cerr << "identify_sweep: --seeds must be >= 1\n";
        return 2;
    }
    if (segments) return segment_study(out_path, seeds);

    const testing::SimulatedRun base;
    const IdentificationOptions defaults;
    IdentificationOptions relaxed;
    relaxed.max_relative_std_error = std::numeric_limits<double>::infinity();
    relaxed.max_stuck_fraction = 1.0;

    ordered_json cells = ordered_json::array();
    std::printf("%8s %8s | %9s %9s %9s | %9s %9s | %8s %8s | %s\n", "length_s", "rms_n", "m_err_%",
                "b_err_%", "Fc_err_%", "wall_ms", "cpu_ms", "iters", "refused", "reasons");
    for (double length : kLengthsS) {
        for (double amplitude : kAmplitudesN) {
            ordered_json runs = ordered_json::array();
            std::vector<double> mass_error, damping_error, coulomb_error, wall, cpu, iterations;
            int refused = 0;
            std::string reasons;
            for (int seed = 1; seed <= seeds; ++seed) {
                testing::SimulatedRun run = base;
                run.duration_s = length;
                run.force_rms_n = amplitude;
                run.seed = static_cast<std::uint64_t>(seed);
                const hapticd::tune::TelemetryLog log = testing::simulated_log(run);
                ordered_json entry = {{"seed", seed}};
                // Would the default options accept it?
                std::string refusal;
                try {
                    hapticd::tune::identify_axis(log, 0, defaults);
                } catch (const IdentificationRefused& e) {
                    refusal = std::string(hapticd::tune::to_string(e.reason()));
                }
                entry["refused_by_default"] =
                    refusal.empty() ? ordered_json(nullptr) : ordered_json(refusal);
                if (!refusal.empty()) {
                    ++refused;
                    if (reasons.find(refusal) == std::string::npos) {
                        reasons += (reasons.empty() ? "" : ",") + refusal;
                    }
                }
                try {
                    const double cpu_start = thread_cpu_s();
                    const IdentifiedAxis fit = hapticd::tune::identify_axis(log, 0, relaxed);
                    const double cpu_s = thread_cpu_s() - cpu_start;
                    const auto& e = fit.estimate;
                    const double em = e.mass_kg / run.mass_kg - 1.0;
                    const double eb = e.damping_n_s_per_m / run.damping_n_s_per_m - 1.0;
                    const double ec = e.coulomb_n / run.coulomb_n - 1.0;
                    entry["mass"] = e.mass_kg;
                    entry["damping"] = e.damping_n_s_per_m;
                    entry["coulomb"] = e.coulomb_n;
                    entry["offset"] = e.offset_n;
                    entry["mass_std_error"] = number(fit.std_error.mass_kg);
                    entry["damping_std_error"] = number(fit.std_error.damping_n_s_per_m);
                    entry["coulomb_std_error"] = number(fit.std_error.coulomb_n);
                    entry["mass_error"] = em;
                    entry["damping_error"] = eb;
                    entry["coulomb_error"] = ec;
                    entry["solve_time_s"] = fit.report.solve_time_s;
                    entry["cpu_time_s"] = cpu_s;
                    entry["iterations"] = fit.report.iterations;
                    entry["stuck_fraction"] = fit.stuck_fraction;
                    entry["converged"] = fit.report.converged;
                    mass_error.push_back(std::abs(em));
                    damping_error.push_back(std::abs(eb));
                    coulomb_error.push_back(std::abs(ec));
                    wall.push_back(fit.report.solve_time_s);
                    cpu.push_back(cpu_s);
                    iterations.push_back(fit.report.iterations);
                } catch (const IdentificationRefused& e) {
                    entry["error"] = e.what();  // refused even with the check off
                }
                runs.push_back(entry);
            }
            ordered_json cell = {
                {"length_s", length},
                {"amplitude_rms_n", amplitude},
                {"runs", runs},
                {"refused_by_default", refused},
                {"median_abs_mass_error", number(median(mass_error))},
                {"median_abs_damping_error", number(median(damping_error))},
                {"median_abs_coulomb_error", number(median(coulomb_error))},
                {"max_abs_mass_error", number(maximum(mass_error))},
                {"max_abs_damping_error", number(maximum(damping_error))},
                {"max_abs_coulomb_error", number(maximum(coulomb_error))},
                {"median_solve_time_s", number(median(wall))},
                {"median_cpu_time_s", number(median(cpu))},
                {"median_iterations", number(median(iterations))},
            };
            std::printf("%8.0f %8.2f | %9.3f %9.3f %9.3f | %9.1f %9.1f | %8.0f %5d/%-2d | %s\n",
                        length, amplitude, 100.0 * median(mass_error),
                        100.0 * median(damping_error), 100.0 * median(coulomb_error),
                        1e3 * median(wall), 1e3 * median(cpu), median(iterations), refused, seeds,
                        reasons.c_str());
            std::fflush(stdout);
            cells.push_back(cell);
        }
    }
    const ordered_json table = {
        {"kind", "identification-sweep"},
        {
            "device",
            {{"mass", base.mass_kg},
             {"damping", base.damping_n_s_per_m},
             {"coulomb", base.coulomb_n},
             {"offset", base.offset_n},
             {"counts_per_meter", base.counts_per_meter},
             {"force_noise_n", base.force_noise_n},
             {"rate_hz", base.rate_hz}},
        },
        {"excitation",
         {{"kind", "Schroeder multisine"},
          {"low_hz", base.low_hz},
          {"high_hz", base.high_hz},
          {"lines", base.lines}}},
        {"segment_s", defaults.segment_s},
        {"max_relative_std_error", defaults.max_relative_std_error},
        {"seeds", seeds},
        {"lengths_s", kLengthsS},
        {"amplitudes_rms_n", kAmplitudesN},
        {"cells", cells},
    };
    return write_json(table, out_path) ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return sweep(argc, argv);
    } catch (const std::exception& e) {
        std::cerr << "identify_sweep: " << e.what() << "\n";
        return 1;
    }
}
