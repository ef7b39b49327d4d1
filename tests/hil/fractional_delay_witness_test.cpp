// HilFractionalDelayWitness: the proof's witness at a fraction of a period of delay (issue 27's
// acceptance), in the unchanged daemon against the sim in lockstep.
//
// The pen display (m = 0.1 kg, b = 2 N s/m, 1 kHz, b_c = 0) with a fraction of a period of
// delay ([device.sim] and [device.model] delay; half a period and three quarters) on the
// stiffest penalty wall a scene allows (1e7 N/m, and the 100 N/m preload of wall_contact.hpp).
// For that scene the passive port condition (docs/stability-models.md, "Every passive
// environment", with the scene's one environment in place of every passive one) proves k_c up
// to k*: 1888 N/m at half a period, against 1600 N/m for every passive environment; 1555
// against 1231 at three quarters. `haptic-tune size --model exact --scene` sizes k*.
//
// Is the proof tight? At a fraction of a period each alias has its own worst operator
// reactance, and for one environment the operators' alias sum must reach the rim point of
// its disk nearest the environment: tune::synthesize_scene_adversaries shapes lossless
// multi-mode grasps alias by alias towards that point (operator_synthesis.hpp). 3 % past k*
// the best of them with at most 8 absorbers (the sim's limit) grows: at half a period 5
// absorbers on the first 3 aliases of 15.9 Hz, by about 1.4e-6 per tick (1.4e-3 /s). The
// test takes it from the exact model, not from a table, and:
// 1. `size` names a witness at 1.03 k* (witness.found), and the daemon with check = "exact"
//    and environments = "scene" refuses 1.03 k* (exit 2) and arms 0.97 k*, proven by the
//    port condition.
// 2. The sim holds that grasp (model = "multi-mode-grasp"); the handle starts 20 um deeper
//    than its rest and the whole force comes on at once (no soft-start ramp), which rings the
//    loop's modes. The component at the witness's frequency is measured by complex
//    demodulation (Hann windows of 2 s, the line through each window removed first) and its
//    log amplitude fitted from 10 s to the end of a 200 s run. Past the proof it grows at the
//    exact model's rate (within 10 %); inside it, the same grasp's mode decays at its rate.
// The other modes of this lossless grasp are marginal (0.13 Hz and 125 Hz, |z| within 1e-8 of
// 1) or far from 15.9 Hz; the window rejects them. The contact holds throughout: the
// handle's excursion stays far below the 0.26 mm at which the tool would leave the wall.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "hapticd/device/sim/sim_config.hpp"
#include "hapticd/theory/passive_model.hpp"
#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/operator_synthesis.hpp"
#include "hapticd/tune/oscillation.hpp"
#include "hapticd_run.hpp"
#include "pen_display.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {
namespace {

using tune::EnvironmentModel;
using tune::OperatorModel;

constexpr double kWallNPerM = 1e7;
constexpr double kFinestCountsPerMeter = 1e10;
constexpr double kKickM = 20e-6;
constexpr double kRunS = 200.0;
constexpr double kFitFromS = 10.0;
constexpr double kDemodulationWindowS = 2.0;

const theory::DeviceModel kPenDisplay{kPenMassKg, kPenDampingNsPerM};

/// What the servo computes in the wall: the massless tool between the coupling, the wall and
/// the preload, the exact model's implicit-Euler mass-spring with m_e = 0 (wall_contact.hpp).
EnvironmentModel linear_wall() {
    return EnvironmentModel::mass_spring(0.0, kWallNPerM + kPreloadStiffnessNPerM, 0.0);
}

/// haptic-tune size --model exact --scene with the delay: the JSON.
nlohmann::json sized_for_the_scene(const ScratchDir& dir, double delay_periods) {
    const std::string scene = dir.write("scene.toml", wall_contact_scene(kWallNPerM));
    const std::string command = shell_quote(HAPTIC_TUNE_BIN) + " size --mass " +
                                toml_number(kPenMassKg) + " --damping " +
                                toml_number(kPenDampingNsPerM) + " --rate " + toml_number(kRateHz) +
                                " --delay " + toml_number(delay_periods * kPeriodS) +
                                " --model exact --scene " + shell_quote(scene) + " --json";
    const CommandResult result = run_command(command);
    EXPECT_EQ(result.exit_code, 0) << command << "\n" << result.err;
    return result.exit_code == 0 ? nlohmann::json::parse(result.out) : nlohmann::json{};
}

/// The scene search's operator with at most the sim's absorbers that grows most at k_c.
OperatorModel worst_shaped_grasp(double stiffness_n_per_m, double delay_periods) {
    const std::vector<tune::SceneEnvironment> scene{{linear_wall(), "the wall"}};
    const std::vector<OperatorModel> adversaries = tune::synthesize_scene_adversaries(
        kPenDisplay, {stiffness_n_per_m, 0.0}, kRateHz, scene, delay_periods);
    OperatorModel worst;
    double worst_radius = 0.0;
    for (const OperatorModel& h : adversaries) {
        if (h.modes.size() > static_cast<std::size_t>(device::sim::kMaxOperatorModes)) continue;
        const double radius = tune::closed_loop_poles(kPenDisplay, {stiffness_n_per_m, 0.0},
                                                      kRateHz, h, linear_wall(), delay_periods)
                                  .spectral_radius;
        if (radius > worst_radius) {
            worst_radius = radius;
            worst = h;
        }
    }
    return worst;
}

/// The grasp as a [device.sim.human] table.
std::string sim_human(const OperatorModel& h) {
    std::string body = "model = \"multi-mode-grasp\"\nhand_mass = " + toml_number(h.hand_mass_kg) +
                       "\nhand_stiffness = " + toml_number(h.hand_stiffness_n_per_m) +
                       "\nhand_damping = " + toml_number(h.hand_damping_n_s_per_m) + "\nmodes = [";
    for (std::size_t i = 0; i < h.modes.size(); ++i) {
        body += std::string(i == 0 ? "" : ", ") + "{ mass = " + toml_number(h.modes[i].mass_kg) +
                ", stiffness = " + toml_number(h.modes[i].stiffness_n_per_m) +
                ", damping = " + toml_number(h.modes[i].damping_n_s_per_m) + " }";
    }
    return human_table(body + "]\n");
}

/// Amplitude of the component of x at `frequency_hz`, by Hann-windowed complex demodulation
/// of windows of kDemodulationWindowS (the least-squares line through each removed first);
/// the windows' middles and ln(amplitude), from `from_s` on.
struct Demodulated {
    std::vector<double> mid_s;
    std::vector<double> log_amplitude;
};

Demodulated demodulate(const std::vector<double>& x, double frequency_hz, double from_s) {
    Demodulated out;
    const auto n = static_cast<std::size_t>(std::lround(kDemodulationWindowS * kRateHz));
    for (auto begin = static_cast<std::size_t>(std::lround(from_s * kRateHz));
         begin + n <= x.size(); begin += n) {
        const std::vector<double> residual = tune::detrended(x, begin, n);
        double in_phase = 0.0, quadrature = 0.0, weights = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const double hann =
                0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                     static_cast<double>(n - 1));
            const double phase =
                2.0 * std::numbers::pi * frequency_hz * static_cast<double>(begin + i) / kRateHz;
            in_phase += hann * residual[i] * std::cos(phase);
            quadrature += hann * residual[i] * std::sin(phase);
            weights += hann;
        }
        out.mid_s.push_back((static_cast<double>(begin) + 0.5 * static_cast<double>(n)) / kRateHz);
        out.log_amplitude.push_back(std::log(2.0 * std::hypot(in_phase, quadrature) / weights));
    }
    return out;
}

/// The closed loop's pole nearest `frequency_hz` (the larger on a tie): its growth per second
/// and its frequency.
struct Mode {
    double growth_per_s = 0.0;
    double frequency_hz = 0.0;
};

Mode mode_near(const tune::ClosedLoopPoles& poles, double frequency_hz) {
    Mode best;
    double best_distance = 1e300;
    for (const theory::Complex& z : poles.eigenvalues) {
        const double f = std::abs(std::arg(z)) * kRateHz / (2.0 * std::numbers::pi);
        const double growth = std::log(std::abs(z)) * kRateHz;
        const double distance = std::abs(f - frequency_hz);
        if (distance < best_distance - 1e-9 ||
            (distance < best_distance + 1e-9 && growth > best.growth_per_s)) {
            best = {growth, f};
            best_distance = distance;
        }
    }
    return best;
}

// NOLINTNEXTLINE(bugprone-exception-escape): nlohmann::json's noexcept move is reported as throwing
struct WitnessRun {
    DaemonRun run;
    Mode predicted;  ///< the followed mode, as the exact model has it
    double growth_per_s = 0.0;
    std::size_t windows = 0;
    double max_outward_m = 0.0;  ///< the handle's largest excursion out of its rest, m
};

/// The grasp in the wall at k_c; the loop's mode nearest `mode_hz` followed.
WitnessRun grasp_in_the_wall(const OperatorModel& grasp, double stiffness_n_per_m,
                             double delay_periods, std::string_view check, double duration_s,
                             double mode_hz) {
    WitnessRun out;
    out.predicted = mode_near(tune::closed_loop_poles(kPenDisplay, {stiffness_n_per_m, 0.0},
                                                      kRateHz, grasp, linear_wall(), delay_periods),
                              mode_hz);
    DaemonConfig config;
    // The check against the scene's own objects, as `size --scene` sized it.
    config.coupling = coupling_table({.stiffness_n_per_m = stiffness_n_per_m}, check) +
                      (check == "off" ? "" : "environments = \"scene\"\n");
    config.model_keys = "delay = " + toml_number(delay_periods * kPeriodS) + "\n";
    config.sim_keys = config.model_keys;
    config.counts_per_meter = kFinestCountsPerMeter;
    const double rest_depth_m = 0.5 / (kWallNPerM + kPreloadStiffnessNPerM);
    config.initial_position = toml_number(rest_depth_m + kKickM);
    config.soft_start_ramp_s = 0.0;
    config.humans = sim_human(grasp);
    const ScratchDir dir;
    out.run = run_hapticd(dir, {.config_toml = config.toml(),
                                .scene_toml = wall_contact_scene(kWallNPerM),
                                .duration_s = duration_s});
    if (out.run.exit_code != 0 || out.run.log.rows() == 0) return out;
    const std::vector<double>& x = out.run.log.column("x0_m");
    for (const double position : x) {
        out.max_outward_m = std::max(out.max_outward_m, rest_depth_m - position);
    }
    const Demodulated component = demodulate(x, out.predicted.frequency_hz, kFitFromS);
    out.windows = component.mid_s.size();
    out.growth_per_s = tune::least_squares_slope(component.mid_s, component.log_amplitude, 0,
                                                 component.mid_s.size());
    std::cout << "[hil] shaped grasp (" << grasp.modes.size() << " absorbers) in a 1e7 N/m wall, "
              << delay_periods << " periods of delay, k_c = " << stiffness_n_per_m << " N/m: the "
              << out.predicted.frequency_hz << " Hz component grows at " << out.growth_per_s
              << " /s over " << out.windows << " windows; exact " << out.predicted.growth_per_s
              << " /s; largest excursion " << out.max_outward_m * 1e6 << " um\n";
    return out;
}

class HilFractionalDelayWitness : public ::testing::TestWithParam<double> {};

TEST_P(HilFractionalDelayWitness, TheScenesShapedGraspGrowsThreePercentPastTheProof) {
    const double delay_periods = GetParam();
    const ScratchDir dir;
    const nlohmann::json sized = sized_for_the_scene(dir, delay_periods);
    ASSERT_TRUE(sized.contains("stiffness")) << sized.dump();
    const double proven_n_per_m = sized.at("stiffness").get<double>();
    EXPECT_EQ(sized.at("proof").get<std::string>(), "the passive port condition");
    // Above what every passive environment allows (the passive model's k_c <= 2b/(τ² T)):
    // the scene buys stiffness.
    const double every_environment_n_per_m =
        2.0 * kPenDampingNsPerM /
        (theory::passive_delay_samples(delay_periods) *
         theory::passive_delay_samples(delay_periods) * kPeriodS);
    EXPECT_GT(proven_n_per_m, 1.1 * every_environment_n_per_m);
    // size's own search finds an operator that grows 3 % past it.
    EXPECT_TRUE(sized.at("witness").at("found").get<bool>()) << sized.at("witness").dump();

    const double past_n_per_m = 1.03 * proven_n_per_m;
    const OperatorModel grasp = worst_shaped_grasp(past_n_per_m, delay_periods);
    ASSERT_FALSE(grasp.modes.empty()) << "the scene search built no grasp the sim can hold";
    std::cout << "[hil] the witness: " << grasp.describe() << "\n";
    const double witness_hz = tune::closed_loop_poles(kPenDisplay, {past_n_per_m, 0.0}, kRateHz,
                                                      grasp, linear_wall(), delay_periods)
                                  .dominant_frequency_hz;

    // The daemon told of the scene and the delay refuses past the proof.
    const WitnessRun refused =
        grasp_in_the_wall(grasp, past_n_per_m, delay_periods, "exact", 1.0, witness_hz);
    EXPECT_EQ(refused.run.exit_code, 2) << refused.run.err;
    EXPECT_NE(refused.run.err.find("NOT unconditionally stable"), std::string::npos)
        << refused.run.err;

    // Past the proof the grasp grows at the exact model's rate.
    const WitnessRun past =
        grasp_in_the_wall(grasp, past_n_per_m, delay_periods, "off", kRunS, witness_hz);
    ASSERT_EQ(past.run.exit_code, 0) << past.run.err;
    ASSERT_GT(past.predicted.growth_per_s, 5e-4);
    EXPECT_GE(past.windows, 90u);
    EXPECT_NEAR(past.growth_per_s, past.predicted.growth_per_s, 0.1 * past.predicted.growth_per_s);
    EXPECT_LT(past.max_outward_m, 0.5 * 0.5 / past_n_per_m);  // the tool never left the wall

    // Inside it, armed on the proof, the same grasp's mode decays at its rate.
    const double inside_n_per_m = 0.97 * proven_n_per_m;
    const WitnessRun inside =
        grasp_in_the_wall(grasp, inside_n_per_m, delay_periods, "exact", kRunS, witness_hz);
    ASSERT_EQ(inside.run.exit_code, 0) << inside.run.err;
    EXPECT_NE(inside.run.err.find("proven by the passive port condition"), std::string::npos)
        << inside.run.err;
    ASSERT_LT(inside.predicted.growth_per_s, -5e-4);
    EXPECT_LT(inside.growth_per_s, 0.0);
    EXPECT_NEAR(inside.growth_per_s, inside.predicted.growth_per_s,
                0.1 * std::abs(inside.predicted.growth_per_s));
}

// Half a period (the case) and three quarters; at a quarter the best grasp of at most 8
// absorbers grows by only 2.3e-4 /s, too slow for a short run.
INSTANTIATE_TEST_SUITE_P(Delays, HilFractionalDelayWitness, ::testing::Values(0.5, 0.75),
                         [](const ::testing::TestParamInfo<double>& param) {
                             return param.param == 0.5 ? std::string("half_a_period")
                                                       : std::string("three_quarters");
                         });

}  // namespace
}  // namespace hapticd::testing
