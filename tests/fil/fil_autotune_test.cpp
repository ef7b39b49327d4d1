// From the emulated board to a stable wall, as docs/firmware.md tells a newcomer to do it, on
// the reference firmware's binary (hapticd-avr-sim in lockstep: deterministic):
//
// 1. `haptic-tune autotune --lockstep` measures the paced loop's delay over the link (diag),
//    runs `hapticd --identify` on the board, identifies the paddle with that delay
//    (docs/identification.md, "Loop delay") and writes gains sized for it. The paddle is the
//    harness's (m 0.05 kg, b 0.5 N s/m) with 0.02 N of Coulomb friction; the identification
//    recovers them within what autotune relies on (2 %, 10 % for friction).
// 2. The delay-aware exact model (tune::closed_loop_poles with the measured fractional delay)
//    puts the stiffest stable coupling, for the handle hands-off against a stiff wall, at k*.
//    Kicked in contact, the board's loop grows at 1.15 k* and decays at 0.87 k*, each at about
//    the rate the model says; the gains autotune wrote (0.9 of the passive bound, which holds
//    for every passive operator) decay too.
//
// The passive bound (400 N/m for this paddle at half a period) lies below k* (about 510 N/m):
// its worst operator is a grasp with modes on many aliases (haptic-tune size names it), which
// the harness's hand cannot be; hands-off against a wall, the delay's phase lag binds at
// k T (1/2 + D/T) = b, the low-frequency limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "emulated_hapkit.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/oscillation.hpp"
#include "hapticd_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {
namespace {

constexpr double kRateHz = 1000.0;
constexpr double kPeriodS = 1.0 / kRateHz;
// hapticd-avr-sim's paddle (its defaults) and the friction given it here.
constexpr double kMassKg = 0.05;
constexpr double kDampingNsPerM = 0.5;
constexpr double kCoulombN = 0.02;
constexpr double kCountM = 1.0 / 81572.06200906535;  ///< the firmware's counts_per_meter

/// The board on the serial plugin; `body` adds [device.model], [coupling], [identify]...
std::string board_config(const std::string& port, const std::string& body) {
    return "[servo]\nrate_hz = 1000.0\nrealtime = \"off\"\n\n"
           "[device]\nplugin = \"serial\"\naxes = 1\n\n"
           "[device.serial]\nport = \"" +
           port + "\"\n\n[safety]\nmax_force = 4.0\nmax_speed = 1.0\n\n" + body;
}

TEST(FilAutotune, IdentifiesThePaddleWithTheMeasuredDelayAndSizesItsCoupling) {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {"--clock", "lockstep", "--coulomb", std::to_string(kCoulombN)});
    // A guess before identification; the paddle's damping is small, so the run plays four
    // periods of the multisine (two leave b at 1.4 % standard error, above autotune's 1 %).
    const std::string config = dir.write(
        "hapkit.toml", board_config(board.port(),
                                    "[device.model]  # a guess\nmass = 0.08\ndamping = 0.8\n"
                                    "coulomb = 0.02\n\n"
                                    "[coupling]\nstiffness = 100.0\ndamping = 0.0\n"
                                    "check = \"passive\"\n\n[identify]\nperiods = 4\n"));
    const CommandResult r =
        run_command(shell_quote(HAPTIC_TUNE_BIN) + " autotune --lockstep --json --config " +
                    shell_quote(config) + " --record " + shell_quote(dir.file("identify.csv")));
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    const nlohmann::json j = nlohmann::json::parse(r.out);

    // The delay: the paced loop's, measured over the link; the identification used its p50,
    // the sizing its p99 rounded up to 0.05 period.
    EXPECT_EQ(j.at("delay_source"), "measured");
    const double p50_periods = j.at("delay_measurement").at("p50_s").get<double>() * kRateHz;
    EXPECT_GT(p50_periods, 0.45);
    EXPECT_LE(p50_periods, 0.5);
    EXPECT_NEAR(j.at("delay_s").get<double>(), 0.0005, 1e-12);
    const nlohmann::json& axis = j.at("axes").at(0);
    EXPECT_DOUBLE_EQ(axis.at("delay_s").get<double>(),
                     j.at("delay_measurement").at("p50_s").get<double>());

    // The paddle, recovered.
    const double mass = axis.at("mass").get<double>();
    const double damping = axis.at("damping").get<double>();
    const double coulomb = axis.at("coulomb").get<double>();
    std::cout << "[fil] autotune identified m " << mass << " +- " << axis.at("mass_std_error")
              << " kg, b " << damping << " +- " << axis.at("damping_std_error") << " N s/m, F_c "
              << coulomb << " +- " << axis.at("coulomb_std_error") << " N (with the delay "
              << p50_periods << " periods); residual " << axis.at("residual_rms_counts")
              << " counts; k_c " << j.at("stiffness") << " N/m\n";
    EXPECT_NEAR(mass, kMassKg, 0.02 * kMassKg);
    EXPECT_NEAR(damping, kDampingNsPerM, 0.02 * kDampingNsPerM);
    EXPECT_NEAR(coulomb, kCoulombN, 0.1 * kCoulombN);
    // The encoder's quantisation and no more: the model (and the delay) fit the board.
    EXPECT_LT(axis.at("residual_rms_counts").get<double>(), 0.35);

    // The gains: 0.9 of the passive bound with the sized delay, written with the model (to
    // six significant digits).
    const double bound = j.at("bound").at("stiffness").get<double>();
    EXPECT_NEAR(j.at("stiffness").get<double>(), 0.9 * bound, 5e-6 * 0.9 * bound);
    EXPECT_NEAR(bound, 400.0, 0.03 * 400.0) << "the true paddle's bound at half a period";
    const daemon::Config tuned = daemon::load_config(config);
    EXPECT_DOUBLE_EQ(tuned.coupling.stiffness_n_per_m, j.at("stiffness").get<double>());
    EXPECT_NEAR(*tuned.device.model.mass_kg, mass, 1e-5 * mass);
    EXPECT_DOUBLE_EQ(tuned.device.model.delay_s, 0.0005);
    board.stop();

    // The config as autotune wrote it renders the demo wall (the embedded default scene:
    // 2e4 N/m, 5 N s/m at x = 0) on a fresh board, the handle pushed into it by 1 N: it
    // settles where the coupling in series with the wall says, and stays.
    const ScratchDir wall_dir;
    EmulatedHapkit pushed(
        wall_dir, {"--clock", "lockstep", "--coulomb", std::to_string(kCoulombN), "--push", "1.0",
                   "--push-start", "0.3", "--push-duration", "100"});
    std::ifstream tuned_in(config);
    std::string text((std::istreambuf_iterator<char>(tuned_in)), std::istreambuf_iterator<char>());
    text.replace(text.find(board.port()), board.port().size(), pushed.port());
    const DaemonRun run =
        run_hapticd(wall_dir, {.config_toml = text, .scene_toml = "", .duration_s = 3.0});
    pushed.stop();
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(fault_list(run), "");
    const auto& t = run.log.column("t_s");
    const auto& x = run.log.column("x0_m");
    double x_min = 1.0, x_max = -1.0, x_sum = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < run.log.rows(); ++i) {
        if (t[i] < 2.0) continue;
        x_min = std::min(x_min, x[i]);
        x_max = std::max(x_max, x[i]);
        x_sum += x[i];
        ++n;
    }
    ASSERT_GT(n, 900);
    const double k_c = tuned.coupling.stiffness_n_per_m;
    std::cout << "[fil] the demo wall at autotune's " << k_c << " N/m: the pushed handle at "
              << 1e3 * x_sum / n << " mm, " << 1e6 * (x_max - x_min) << " um peak to peak\n";
    // 1 N less the paddle's friction, through k_c in series with the wall.
    EXPECT_NEAR(x_sum / n, (1.0 / k_c + 1.0 / 2.0e4), kCoulombN * (1.0 / k_c + 1.0 / 2.0e4) + 1e-4);
    EXPECT_LT(x_max - x_min, 1e-4) << "the handle did not settle at the wall";
}

// ---- 2. Where the board's loop grows -------------------------------------------------------

/// A stiff wall at x = 0 (free space x < 0) with a 2 N preload (a 200 N/m spring anchored
/// 10 mm inside): the tool stays in the wall while the handle's outward swing is under
/// 2 N / k_c (3.6 mm at 550 N/m).
constexpr double kWallNPerM = 1e5;
constexpr double kPreloadNPerM = 200.0;
const std::string kWallScene =
    "[scene]\nname = \"fil-wall\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\noffset = 0.0\n"
    "stiffness = 1e5\ndamping = 0.0\n[[spring]]\nanchor = [0.01]\nstiffness = 200.0\n";
/// The kick: 0.5 N into the wall for 10 ms at 1 s (the handle at rest in contact by then):
/// about 1 mm of swing.
const std::vector<std::string> kKick = {"--push",          "0.5", "--push-start", "1.0",
                                        "--push-duration", "0.01"};
constexpr double kJudgeFromS = 1.05;
constexpr double kRunS = 5.0;

struct Prediction {
    double growth_per_s = 0.0;
    double frequency_hz = 0.0;
};

Prediction predict(double stiffness_n_per_m, double delay_periods) {
    const tune::ClosedLoopPoles poles = tune::closed_loop_poles(
        {kMassKg, kDampingNsPerM}, {stiffness_n_per_m, 0.0}, kRateHz,
        tune::OperatorModel::hands_off(),
        tune::EnvironmentModel::mass_spring(0.0, kWallNPerM + kPreloadNPerM, 0.0), delay_periods);
    return {std::log(poles.spectral_radius) * kRateHz, poles.dominant_frequency_hz};
}

/// The stiffest k_c whose loop the exact model finds stable, to 0.01 %.
double exact_bound(double delay_periods) {
    double stable = 100.0, unstable = 2000.0;
    while (unstable - stable > 1e-4 * stable) {
        const double mid = 0.5 * (stable + unstable);
        (predict(mid, delay_periods).growth_per_s < 0.0 ? stable : unstable) = mid;
    }
    return stable;
}

/// The paced loop's delay, as haptic-tune diag measures it on a fresh board (p50, periods).
double measured_delay_periods() {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {"--clock", "lockstep"});
    const std::string config =
        dir.write("cfg.toml", board_config(board.port(),
                                           "[device.model]\nmass = 0.05\n"
                                           "damping = 0.5\ndelay = 0.0005\n"));
    const CommandResult diag =
        run_command(shell_quote(HAPTIC_TUNE_BIN) +
                    " diag --lockstep --duration 0.5 --json --config " + shell_quote(config));
    board.stop();
    const nlohmann::json report = nlohmann::json::parse(diag.out);
    return report.at("loop_delay").at("periods").at("p50").get<double>();
}

struct Contact {
    double growth_per_s = 0.0;  ///< over the linear phase
    std::size_t windows = 0;
    Prediction predicted;
    double peak_m = 0.0;
};

/// The handle kicked in contact with the wall through k_c on the board.
Contact kicked_contact(double stiffness_n_per_m, double delay_periods) {
    const ScratchDir dir;
    std::vector<std::string> options = {"--clock", "lockstep"};
    options.insert(options.end(), kKick.begin(), kKick.end());
    EmulatedHapkit board(dir, options);
    std::ostringstream body;
    body.precision(17);
    body << "[device.model]\nmass = 0.05\ndamping = 0.5\ndelay = 0.0005\n\n"
         << "[coupling]\nstiffness = " << stiffness_n_per_m
         << "\ndamping = 0.0\ncheck = \"off\"\n\n[scene]\nfile = \"" << dir.file("scene.toml")
         << "\"\n";
    const DaemonRun run = run_hapticd(dir, {.config_toml = board_config(board.port(), body.str()),
                                            .scene_toml = kWallScene,
                                            .duration_s = kRunS});
    board.stop();
    Contact out;
    out.predicted = predict(stiffness_n_per_m, delay_periods);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(fault_list(run), "");
    if (run.log.rows() == 0) return out;
    const auto& x = run.log.column("x0_m");
    const auto& xe = run.log.column("xe0_m");
    const auto first = static_cast<std::size_t>(std::lround(kJudgeFromS * kRateHz));
    const auto window =
        static_cast<std::size_t>(std::lround(2.0 * kRateHz / out.predicted.frequency_hz));
    const double floor_m = 3.0 * kCountM;
    const tune::OscillationTrend trend =
        tune::oscillation_trend(x, kPeriodS, first, window, floor_m);
    // Linear while the tool stays in the wall (2 N / k_c each way) and the force swings over
    // several of the PWM's steps (a duty step is 31 mN: 5 of them peak to peak).
    const double contact_p2p_m = 2.0 * 2.0 / stiffness_n_per_m;
    const double duty_step_m = 7.975 / 256 / stiffness_n_per_m;
    out.growth_per_s = tune::linear_phase_growth_per_s(
        trend, std::max(5.0 * duty_step_m, 10 * floor_m), 0.8 * contact_p2p_m, out.windows);
    out.peak_m = trend.peak_amplitude_m;
    double min_depth = 1.0;
    for (std::size_t i = first; i < xe.size(); ++i) min_depth = std::min(min_depth, xe[i]);
    std::cout << "[fil] k_c " << stiffness_n_per_m << " N/m: growth " << out.growth_per_s
              << " /s over " << out.windows << " windows of " << trend.window_s
              << " s (exact model " << out.predicted.growth_per_s << " /s at "
              << out.predicted.frequency_hz << " Hz); amplitude " << 1e3 * trend.first_amplitude_m
              << " -> peak " << 1e3 * trend.peak_amplitude_m << " -> last "
              << 1e3 * trend.last_amplitude_m << " mm p-p; min tool depth " << 1e6 * min_depth
              << " um\n";
    return out;
}

TEST(FilStability, TheBoardsLoopGrowsPastTheDelayAwareBoundAndDecaysBelowIt) {
    const double delay_periods = measured_delay_periods();
    const double k_star = exact_bound(delay_periods);
    std::cout << "[fil] measured delay " << delay_periods << " periods: exact bound " << k_star
              << " N/m hands-off against the wall (b/(T (1/2 + D/T)) = "
              << kDampingNsPerM / (kPeriodS * (0.5 + delay_periods)) << ")\n";
    EXPECT_GT(k_star, 480.0);
    EXPECT_LT(k_star, 540.0);

    const Contact above = kicked_contact(1.15 * k_star, delay_periods);
    EXPECT_GT(above.predicted.growth_per_s, 0.3);
    EXPECT_GE(above.windows, 3u);
    EXPECT_GT(above.growth_per_s, 0.0) << "the loop did not grow past the bound";
    EXPECT_NEAR(above.growth_per_s, above.predicted.growth_per_s,
                0.3 * above.predicted.growth_per_s);

    const Contact below = kicked_contact(0.87 * k_star, delay_periods);
    EXPECT_LT(below.predicted.growth_per_s, -0.3);
    EXPECT_GE(below.windows, 3u);
    EXPECT_LT(below.growth_per_s, 0.0) << "the loop did not decay under the bound";
    EXPECT_NEAR(below.growth_per_s, below.predicted.growth_per_s,
                0.3 * std::abs(below.predicted.growth_per_s));

    // autotune's gains for this paddle: 0.9 of the passive bound at half a period.
    const Contact tuned = kicked_contact(0.9 * 400.0, delay_periods);
    EXPECT_LT(tuned.growth_per_s, below.growth_per_s) << "softer gains decay faster";
}

}  // namespace
}  // namespace hapticd::testing
