// hapticd-avr-sim: the reference firmware's ELF on an emulated ATmega328P (simavr) inside an
// emulated Hapkit paddle, its UART on a pseudo-terminal that hapticd's serial plugin opens as
// it would the real board (docs/firmware.md, "The firmware in the loop").
//
// This program links simavr and is therefore GPL-3.0-or-later as built; hapticd and its
// libraries never link it.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "emulated_board.hpp"
#include "hapticd/servo/nearest_rank.hpp"
#include "harness.hpp"
#include "parse_command_line.hpp"
#include "pty_link.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) { g_stop.store(true); }

nlohmann::json figures_json(const hapticd::avr_sim::HarnessFigures& f,
                            const hapticd::avr_sim::EmulatedBoard& board) {
    const hapticd::avr_sim::PaddlePlant& plant = board.plant();
    const auto stats = [](const std::vector<double>& values) {
        return nlohmann::json{{"count", values.size()},
                              {"p50", hapticd::servo::quantile(values, 0.5)},
                              {"p99", hapticd::servo::quantile(values, 0.99)},
                              {"max", hapticd::servo::quantile(values, 1.0)}};
    };
    const nlohmann::json compute = stats(f.compute_us);
    return {{"requests", f.requests},
            {"replies", f.replies},
            {"device_latency_us", stats(f.latency_us)},
            {"device_compute_us", compute},
            {"host_turnaround_us", stats(f.turnaround_us)},
            {"loop_delay_us", stats(f.loop_delay_us)},
            {"receive_overruns", board.receive_overruns()},
            {"emulated_s", f.emulated_s},
            {"wall_s", f.wall_s},
            {"lag_max_s", f.lag_max_s},
            {"position_m", plant.position_m()},
            {"velocity_mps", plant.velocity_mps()},
            {"counts_per_meter", plant.mr_counts_per_meter()},
            {"full_duty_force_n", plant.full_duty_force_n()}};
}

int run(int argc, char** argv) {
    using namespace hapticd::avr_sim;
    CLI::App app{
        "hapticd-avr-sim: the reference firmware on an emulated ATmega328P in an emulated "
        "Hapkit paddle, its serial port on a pseudo-terminal (docs/firmware.md). GPL-3.0-or-later "
        "as built: it links simavr.",
        "hapticd-avr-sim"};
    app.set_version_flag("--version", std::string("hapticd-avr-sim ") + HAPTICD_VERSION +
                                          " (simavr; GPL-3.0-or-later as built)");
    std::string firmware, link, clock = "real-time", sensor = "mr", op = "hands-off", stats, record;
    PaddleConfig paddle;
    HarnessOptions options;
    double plant_step_s = 4e-6;
    const auto positive = CLI::PositiveNumber;
    app.add_option("--firmware", firmware, "the firmware ELF (build/release/firmware/hapkit.elf)")
        ->required()
        ->check(CLI::ExistingFile);
    app.add_option("--link", link, "the path to make the board's serial port at (a symlink)")
        ->required();
    app.add_option("--clock", clock,
                   "real-time: emulated time held to the wall clock; lockstep: one period of "
                   "emulated time per request (for hapticd --lockstep)")
        ->check(CLI::IsMember({"real-time", "lockstep"}))
        ->capture_default_str();
    app.add_option("--period", options.period_s, "lockstep: emulated seconds per request")
        ->check(CLI::Range(1e-5, 1.0))
        ->capture_default_str();
    app.add_option("--duration", options.duration_s,
                   "emulated seconds to run, then exit 0; 0: until SIGINT or SIGTERM")
        ->check(CLI::Range(0.0, 1e6))
        ->capture_default_str();
    app.add_option("--sensor", sensor, "the firmware's position sensor: mr or quadrature")
        ->check(CLI::IsMember({"mr", "quadrature"}))
        ->capture_default_str();
    app.add_option("--mass", paddle.mass_kg, "the handle's mass (kg)")
        ->check(CLI::Range(1e-4, 100.0))
        ->capture_default_str();
    app.add_option("--damping", paddle.damping_n_s_per_m, "viscous damping (N s/m)")
        ->check(CLI::Range(0.0, 1e3))
        ->capture_default_str();
    app.add_option("--coulomb", paddle.coulomb_n, "dry friction (N)")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    app.add_option("--initial-position", paddle.initial_position_m,
                   "the handle at power-up (m), where the firmware's counts are zero")
        ->check(CLI::Range(-1.0, 1.0))
        ->capture_default_str();
    app.add_option("--torque-at-full-duty", paddle.torque_at_full_duty_nm,
                   "motor torque at 100 % duty (N m)")
        ->check(positive)
        ->capture_default_str();
    app.add_option("--handle-radius", paddle.kinematics.handle_radius_m, "(m)")
        ->check(positive)
        ->capture_default_str();
    app.add_option("--sector-radius", paddle.kinematics.sector_radius_m, "(m)")
        ->check(positive)
        ->capture_default_str();
    app.add_option("--capstan-radius", paddle.kinematics.capstan_radius_m, "(m)")
        ->check(positive)
        ->capture_default_str();
    app.add_option("--mr-counts-per-flip", paddle.mr_counts_per_flip,
                   "the MR sensor's ADC counts per half turn of the motor")
        ->check(CLI::Range(100, 1000))
        ->capture_default_str();
    app.add_option("--encoder-counts-per-rev", paddle.encoder_counts_per_rev,
                   "--sensor quadrature: counts per motor turn after x4 decoding")
        ->check(CLI::Range(4, 1'000'000))
        ->capture_default_str();
    app.add_option("--operator", op, "hands-off, or hand (--hand-*)")
        ->check(CLI::IsMember({"hands-off", "hand"}))
        ->capture_default_str();
    app.add_option("--hand-mass", paddle.human.mass_kg, "(kg)")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    app.add_option("--hand-stiffness", paddle.human.stiffness_n_per_m, "to --hand-rest (N/m)")
        ->check(CLI::Range(0.0, 1e7))
        ->capture_default_str();
    app.add_option("--hand-damping", paddle.human.damping_n_s_per_m, "(N s/m)")
        ->check(CLI::Range(0.0, 1e4))
        ->capture_default_str();
    app.add_option("--hand-rest", paddle.human.rest_m, "(m)")
        ->check(CLI::Range(-1.0, 1.0))
        ->capture_default_str();
    app.add_option("--push", paddle.human.push_n, "a push on the handle (N), with any operator")
        ->check(CLI::Range(-100.0, 100.0))
        ->capture_default_str();
    app.add_option("--push-start", paddle.human.push_start_s, "(emulated s)")
        ->check(CLI::Range(0.0, 1e6))
        ->capture_default_str();
    app.add_option("--push-duration", paddle.human.push_duration_s, "(s)")
        ->check(CLI::Range(0.0, 1e6))
        ->capture_default_str();
    app.add_option("--plant-step", plant_step_s, "the paddle's integration step (s)")
        ->check(CLI::Range(1e-7, 1e-4))
        ->capture_default_str();
    app.add_option("--record", record,
                   "write the motor pins and the paddle as CSV: a row per --record-interval and "
                   "one whenever a pin changes");
    app.add_option("--record-interval", options.record_interval_s, "(s)")
        ->check(CLI::Range(1e-6, 1.0))
        ->capture_default_str();
    app.add_option("--stats", stats, "write the run's figures as JSON (also on stderr)");
    std::string profile;
    app.add_option(
        "--profile", profile,
        "write where the firmware spent its time from each request's last byte in to its "
        "reply's first byte out: 'address samples' per line, the program counter "
        "sampled every 7 cycles (map the addresses with avr-nm)");
    if (const auto exit_code = hapticd::tools::parse_command_line(app, argc, argv)) {
        return *exit_code;
    }
    paddle.human.kind = op == "hand" ? PaddleOperator::Kind::hand : PaddleOperator::Kind::hands_off;
    options.clock = clock == "lockstep" ? Clock::lockstep : Clock::real_time;
    options.record_path = record;
    try {
        EmulatedBoard board(
            firmware, paddle,
            sensor == "quadrature" ? PositionSensor::quadrature : PositionSensor::mr, plant_step_s);
        // The firmware boots (its UART on, the sensor's zero taken) before the port appears,
        // so that a host's first bytes are never lost to an MCU still starting.
        board.run_until(board.cycle() + EmulatedBoard::kCpuHz / 100);
        PtyLink pty(link);
        std::signal(SIGINT, on_signal);
        std::signal(SIGTERM, on_signal);
        std::cerr << "hapticd-avr-sim: " << firmware << " on " << link << " -> " << pty.slave_path()
                  << ", clock " << clock << "\n";
        if (!profile.empty()) board.start_profile(7);
        Harness harness(board, pty, options);
        const HarnessFigures figures = harness.run(g_stop);
        const nlohmann::json report = figures_json(figures, board);
        std::cerr << "hapticd-avr-sim: " << report.dump() << "\n";
        if (!profile.empty()) {
            std::ofstream out(profile);
            for (const auto& [address, samples] : board.profile()) {
                out << address << ' ' << samples << '\n';
            }
        }
        if (!stats.empty()) {
            std::ofstream out(stats);
            out << report.dump(2) << "\n";
            if (!out) {
                std::cerr << "hapticd-avr-sim: cannot write --stats " << stats << "\n";
                return 1;
            }
        }
    } catch (const std::exception& error) {
        std::cerr << "hapticd-avr-sim: " << error.what() << "\n";
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << "hapticd-avr-sim: " << error.what() << "\n";
    } catch (...) {
        std::cerr << "hapticd-avr-sim: an unknown exception\n";
    }
    return 1;
}
