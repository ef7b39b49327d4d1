// HilIdentify: `hapticd --identify`, the excitation run, end to end: the real executable
// drives the sim plugin (config/hapticd.toml's pen display, hands off) in lockstep with the
// [identify] multisine, and the telemetry CSV it writes is judged by value: complete, the
// commanded force is the signal to the last bit, the handle stays in the workspace, and a
// handle that leaves it gets zero force from that tick on. Plus the refusals, and the
// daemon's own loop with the excitation under the allocation guard.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>

#include "alloc_guard.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/device/plugin_loader.hpp"
#include "hapticd/env/excitation.hpp"
#include "hapticd/servo/servo_loop.hpp"
#include "hapticd_run.hpp"

namespace hapticd::testing {
namespace {

/// config/hapticd.toml's simulated pen display (m = 0.1 kg, b = 2 N s/m, 10 um counts,
/// 20 N), hands off, starting 1 cm in front of the origin; `identify` is the [identify]
/// table's body.
std::string pen_config(const std::string& identify = "", int axes = 1) {
    std::ostringstream out;
    out << "[servo]\nrate_hz = 1000.0\n"
        << "[device]\nplugin = \"sim\"\naxes = " << axes << "\n"
        << "[device.model]\nmass = 0.1\ndamping = 2.0\n"
        << "[coupling]\nstiffness = 3600.0\ndamping = 0.0\ncheck = \"encoder\"\n"
        << "[safety]\nmax_force = 20.0\nmax_speed = 1.0\n"
        << "[device.sim]\nmass = 0.1\ndamping = 2.0\ncounts_per_meter = 1e5\n"
        << "force_limit = 20.0\ninitial_position = -0.01\n"
        << "[device.sim.human]\nmodel = \"hands-off\"\n"
        << "[identify]\n"
        << identify;
    return out.str();
}

/// hapticd --identify --lockstep on `config_toml`; `with_log` false leaves out --log.
DaemonRun run_identify(const ScratchDir& dir, const std::string& config_toml,
                       bool with_log = true) {
    return run_hapticd(dir, {.config_toml = config_toml,
                             .scene_toml = "",
                             .duration_s = 0.0,  // the excitation's own length
                             .lockstep = true,
                             .identify = true,
                             .with_log = with_log});
}

/// The excitation the daemon builds for `config_toml` on the sim device (20 N, lockstep).
env::ExcitationEnvironment planned_excitation(const std::string& config_toml, int axes = 1) {
    const daemon::Config config = daemon::parse_config(config_toml, "cfg.toml", "");
    device::DeviceInfo info;
    info.axes = axes;
    info.counts_per_meter = 1e5;
    info.force_limit_n = 20.0;
    info.paces_loop = true;
    info.lockstep = true;
    info.name = "sim";
    return env::ExcitationEnvironment(daemon::make_identify_plan(config, info).excitation);
}

/// The force of excitation sample j on `axis` from the line list (amplitude, phase,
/// harmonic) and the envelope, not from the table: an independent reading of the signal.
double from_lines(const env::ExcitationEnvironment& e, int axis, std::int64_t j) {
    return e.envelope(j) * e.signal().evaluate_lines(axis, j - e.fade_samples());
}

// The hands-off handle is still from the first tick: the excitation starts after the
// still wait, at tick 200.
constexpr std::int64_t kStartTick = 200;

TEST(HilIdentify, PenDisplayLogsTheSignalItCommandedAndStaysInTheWorkspace) {
    const ScratchDir dir;
    const std::string config = pen_config();
    const DaemonRun run = run_identify(dir, config);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const env::ExcitationEnvironment e = planned_excitation(config);

    // What the run says it is (and is not).
    EXPECT_NE(run.err.find("the start-up stability check does not apply"), std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find("the excitation ran to its end"), std::string::npos) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "duration");
    EXPECT_TRUE(run.summary.at("faults").empty());
    EXPECT_EQ(run.summary.at("stability_check").at("model"),
              "none (identify: open loop, nothing coupled)");
    EXPECT_EQ(run.summary.at("saturated_ticks"), 0);

    // Complete: the columns of docs/architecture.md §4.5, one row per tick of the whole
    // excitation and its tail.
    EXPECT_EQ(run.log_header,
              "tick,t_s,unix_time_s,x0_m,v0_mps,xe0_m,f0_n,status,tick_flags,faults,state,"
              "wake_latency_us,compute_us,energy_j,mark");
    const std::size_t expected_rows = static_cast<std::size_t>(kStartTick + e.samples() + 500);
    ASSERT_EQ(run.log.rows(), expected_rows);
    EXPECT_EQ(run.summary.at("telemetry_records"), expected_rows);
    const auto& tick = run.log.column("tick");
    const auto& t = run.log.column("t_s");
    const auto& x = run.log.column("x0_m");
    const auto& f = run.log.column("f0_n");
    const auto& faults = run.log.column("faults");
    for (std::size_t row = 0; row < run.log.rows(); ++row) {
        ASSERT_EQ(tick[row], static_cast<double>(row));
        ASSERT_NEAR(t[row], 1e-3 * static_cast<double>(row), 1e-12);
        ASSERT_EQ(faults[row], 0.0);
    }

    // f0_n is the signal: bit for bit against the planned table, and against the line
    // formula to rounding; zero before the start and after the end.
    std::size_t bit_mismatches = 0;
    double formula_error = 0.0, swing = 0.0;
    const double start_x = x[static_cast<std::size_t>(kStartTick)];
    for (std::size_t row = 0; row < run.log.rows(); ++row) {
        const std::int64_t j = static_cast<std::int64_t>(row) - kStartTick;
        if (f[row] != e.scheduled_force_n(j).x) ++bit_mismatches;
        formula_error = std::max(formula_error, std::abs(f[row] - from_lines(e, 0, j)));
        swing = std::max(swing, std::abs(x[row] - start_x));
    }
    EXPECT_EQ(bit_mismatches, 0u);
    EXPECT_LT(formula_error, 1e-12);
    EXPECT_EQ(f[static_cast<std::size_t>(kStartTick - 1)], 0.0);
    EXPECT_EQ(f.back(), 0.0);
    EXPECT_EQ(start_x, -0.01);  // hands off: the handle waited where it started

    // Inside the workspace, and about as far as the model said.
    const double workspace = e.settings().workspace_half_width_m;
    const double predicted = e.signal().steady_state_excursion_m(0.1, 2.0);
    std::cout << "[hil] identify, pen display: " << run.log.rows() << " rows, peak force "
              << e.signal().settings().peak_force_n << " N, swing +-" << 1e3 * swing
              << " mm (predicted +-" << 1e3 * predicted << " mm, workspace +-" << 1e3 * workspace
              << " mm), max |f - lines| " << formula_error << " N\n";
    EXPECT_LE(swing, workspace);
    EXPECT_NEAR(swing, predicted, 0.15 * predicted);
}

TEST(HilIdentify, LeavingTheWorkspaceZeroesTheForceThatTickAndForTheRestOfTheRun) {
    const ScratchDir dir;
    // 2 N on a 0.1 kg pen swings about +-40 mm; the box is +-10 mm. Told so, hapticd refuses
    // the run before it starts (HilIdentify.ARunThatWouldLeaveTheWorkspaceIsRefusedBeforeItMoves);
    // a model five times too heavy (the same corner) predicts +-8 mm, so the run starts and
    // the rule stops it.
    std::string config = pen_config("force_amplitude = 2.0\nworkspace = 0.01\n");
    config.replace(config.find("mass = 0.1\ndamping = 2.0"), 24, "mass = 0.5\ndamping = 10.0");
    const DaemonRun run = run_identify(dir, config);
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.summary.at("exit"), "workspace");
    EXPECT_TRUE(run.summary.at("faults").empty());
    EXPECT_NE(run.err.find("the handle left the workspace at tick"), std::string::npos) << run.err;
    const env::ExcitationEnvironment e = planned_excitation(config);
    ASSERT_EQ(run.log.rows(), static_cast<std::size_t>(kStartTick + e.samples() + 500));
    const auto& x = run.log.column("x0_m");
    const auto& f = run.log.column("f0_n");
    const double centre = x[static_cast<std::size_t>(kStartTick)];
    std::size_t exit_row = 0;
    for (std::size_t row = kStartTick; row < run.log.rows(); ++row) {
        if (std::abs(x[row] - centre) > 0.01) {
            exit_row = row;
            break;
        }
    }
    ASSERT_GT(exit_row, 0u) << "the handle never left the workspace";
    for (std::size_t row = 0; row < exit_row; ++row) {
        ASSERT_EQ(f[row], e.scheduled_force_n(static_cast<std::int64_t>(row) - kStartTick).x)
            << "row " << row;
    }
    EXPECT_NE(f[exit_row - 1], 0.0);
    std::size_t nonzero_after = 0;
    for (std::size_t row = exit_row; row < run.log.rows(); ++row) nonzero_after += f[row] != 0.0;
    std::cout << "[hil] identify, 2 N in +-10 mm: left at t = " << 1e-3 * exit_row
              << " s (x = " << 1e3 * (x[exit_row] - centre) << " mm from the start); "
              << nonzero_after << " rows with force after it, of " << run.log.rows() - exit_row
              << "\n";
    EXPECT_EQ(nonzero_after, 0u);
}

TEST(HilIdentify, TwoAxesEachGetTheirOwnLinesAndStayInTheWorkspace) {
    const ScratchDir dir;
    const std::string config = pen_config("", 2);
    const DaemonRun run = run_identify(dir, config);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const env::ExcitationEnvironment e = planned_excitation(config, 2);
    ASSERT_EQ(run.log.rows(), static_cast<std::size_t>(kStartTick + e.samples() + 500));
    for (int axis = 0; axis < 2; ++axis) {
        const auto& f = run.log.column("f" + std::to_string(axis) + "_n");
        const auto& x = run.log.column("x" + std::to_string(axis) + "_m");
        const double start_x = x[static_cast<std::size_t>(kStartTick)];
        double swing = 0.0;
        std::size_t mismatches = 0;
        for (std::size_t row = 0; row < run.log.rows(); ++row) {
            const std::int64_t j = static_cast<std::int64_t>(row) - kStartTick;
            mismatches += f[row] != e.scheduled_force_n(j)[axis];
            swing = std::max(swing, std::abs(x[row] - start_x));
        }
        EXPECT_EQ(mismatches, 0u) << "axis " << axis;
        EXPECT_LE(swing, e.settings().workspace_half_width_m) << "axis " << axis;
        // By value over the whole periods of the log: this axis's lines, not the other's.
        const std::size_t begin = static_cast<std::size_t>(kStartTick + e.fade_samples());
        const std::size_t length =
            static_cast<std::size_t>(e.settings().periods) * e.signal().period_samples();
        auto amplitude_at = [&](int harmonic) {
            std::complex<double> sum = 0.0;
            for (std::size_t n = 0; n < length; ++n) {
                const double angle = -2.0 * std::numbers::pi *
                                     static_cast<double>((harmonic * n) % length) /
                                     static_cast<double>(length);
                sum += f[begin + n] * std::polar(1.0, angle);
            }
            return 2.0 * std::abs(sum) / static_cast<double>(length);
        };
        const int periods = e.settings().periods;
        for (int line_axis = 0; line_axis < 2; ++line_axis) {
            for (const env::MultisineLine& line : e.signal().lines(line_axis)) {
                const double measured = amplitude_at(periods * line.harmonic);
                if (line_axis == axis) {
                    EXPECT_NEAR(measured, line.amplitude_n, 1e-9);
                } else {
                    EXPECT_LT(measured, 1e-9);
                }
            }
        }
        std::cout << "[hil] identify, 2 axes: axis " << axis << ": "
                  << e.signal().lines(axis).size() << " lines from "
                  << e.signal().lines(axis).front().frequency_hz << " Hz, swing +-" << 1e3 * swing
                  << " mm\n";
    }
}

TEST(HilIdentify, ARunThatWouldLeaveTheWorkspaceIsRefusedBeforeItMoves) {
    const ScratchDir dir;
    const DaemonRun run =
        run_identify(dir, pen_config("force_amplitude = 2.0\nworkspace = 0.01\n"));
    EXPECT_EQ(run.exit_code, 2);
    EXPECT_NE(run.err.find("[identify] force_amplitude = 2 N: [device.model] (m = 0.1 kg, b = 2 "
                           "N s/m) predicts the handle swings +-"),
              std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find("Lower force_amplitude to <= "), std::string::npos) << run.err;
    EXPECT_EQ(run.log.rows(), 0u) << "nothing moved: the refusal comes before the first tick";
}

TEST(HilIdentify, ARunFrictionWouldHoldStillIsRefusedBeforeItMoves) {
    const ScratchDir dir;
    std::string config = pen_config("force_amplitude = 0.3\n");
    config.replace(config.find("damping = 2.0\n"), 14, "damping = 2.0\ncoulomb = 0.2\n");
    const DaemonRun run = run_identify(dir, config);
    EXPECT_EQ(run.exit_code, 2);
    EXPECT_NE(run.err.find("predicts Coulomb friction holds the handle still after"),
              std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find("Raise force_amplitude to >= "), std::string::npos) << run.err;
    EXPECT_EQ(run.log.rows(), 0u);
}

TEST(HilIdentify, NeedsALogFile) {
    const ScratchDir dir;
    const DaemonRun run = run_identify(dir, pen_config(), /*with_log=*/false);
    EXPECT_EQ(run.exit_code, 2);
    EXPECT_NE(run.err.find("--identify needs --log FILE"), std::string::npos) << run.err;
}

TEST(HilIdentify, BadIdentifyKeysAreRejectedByName) {
    const ScratchDir dir;
    const DaemonRun typo = run_identify(dir, pen_config("forse_amplitude = 1.0\n"));
    EXPECT_EQ(typo.exit_code, 2);
    EXPECT_NE(typo.err.find("[identify] forse_amplitude = 1.0 is not a known key"),
              std::string::npos)
        << typo.err;
    EXPECT_EQ(typo.log.rows(), 0u);
    const DaemonRun range = run_identify(dir, pen_config("workspace = -0.01\n"));
    EXPECT_EQ(range.exit_code, 2);
    EXPECT_NE(range.err.find("[identify] workspace = -0.01 is out of range"), std::string::npos)
        << range.err;
    const DaemonRun too_strong = run_identify(dir, pen_config("force_amplitude = 25\n"));
    EXPECT_EQ(too_strong.exit_code, 2);
    EXPECT_NE(too_strong.err.find("[identify] force_amplitude = 25 is out of range: allowed <= "
                                  "[safety] max_force = 20"),
              std::string::npos)
        << too_strong.err;
}

// The daemon's loop with the excitation, as run_daemon wires it for --identify (the sim
// plugin through the plugin loader, make_identify_servo_config, the planned excitation),
// under the allocation guard for the whole excitation.
TEST(HilIdentify, TicksOfTheExcitationDoNotAllocate) {
    const std::string text = pen_config("", 3);
    const daemon::Config config = daemon::parse_config(text, "hil-identify.toml", "");
    device::DeviceHandle device = device::load_device("sim");
    device::DeviceConfig device_config;
    device_config.axes = 3;
    device_config.rate_hz = config.servo.rate_hz;
    device_config.lockstep = true;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.plugin_table_path = config.device.plugin_table_path;
    device_config.source = config.source;
    device->open(device_config);
    const device::DeviceInfo info = device->info();
    const servo::ServoConfig servo_config = daemon::make_identify_servo_config(config, info, false);
    env::ExcitationEnvironment excitation(daemon::make_identify_plan(config, info).excitation);
    std::uint64_t allocations = 0;
    {
        servo::ServoLoop<device::Device, env::ExcitationEnvironment> loop(*device, excitation,
                                                                          servo_config);
        const std::atomic<bool> stop{false};
        (void)loop.run(stop, 10);  // the first ticks, outside the guard
        const AllocationGuard guard;
        (void)loop.run(stop, static_cast<std::uint64_t>(excitation.samples() + 500));
        allocations = guard.allocations();
        EXPECT_EQ(loop.faults_seen(), 0u);
    }
    device->close();
    std::cout << "[hil] identify, 3 axes: " << allocations << " allocations in "
              << excitation.samples() + 500 << " ticks\n";
    EXPECT_EQ(allocations, 0u);
    EXPECT_EQ(excitation.phase(), env::ExcitationEnvironment::Phase::finished);
}

}  // namespace
}  // namespace hapticd::testing
