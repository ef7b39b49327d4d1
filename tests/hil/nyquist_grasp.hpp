// The issue's two-mass grasp on the stiff wall, and the fit of its alternating component:
// the experiment HilDelayedCoupling 4 and HilFilteredCoupling share (their file comments).
// The handle and the grasp's set-point start 1 mm inside the wall with the sim's finest
// encoder; the step of the coupling force when the soft start ends rings the grasp's modes,
// and the alternating component y[n] = (-1)^n (x[n] - x[n-1]) / 2 is fitted, as ln of its RMS
// in 0.1 s windows, from 8 s until it falls to 100 encoder counts.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <optional>
#include <regex>
#include <string>
#include <string_view>
#include <vector>

#include "hapticd/tune/exact_model.hpp"
#include "hapticd/tune/oscillation.hpp"
#include "hapticd_run.hpp"
#include "pen_display.hpp"

namespace hapticd::testing {

// The grasp: skin 7.926e6 N/m, hand 0.946 kg, arm 1.0464e7 N/m, no damping. Its free-handle
// modes sit on 500 Hz and 1500 Hz, the first two odd harmonics of Nyquist.
inline constexpr double kSkinStiffnessNPerM = 7.926e6;
inline constexpr double kGraspHandMassKg = 0.946;
inline constexpr double kArmStiffnessNPerM = 1.0464e7;
inline constexpr double kStiffestWallNPerM = 1e7;      ///< the scene's upper limit (docs/scenes.md)
inline constexpr double kFinestCountsPerMeter = 1e10;  ///< 0.1 nm, the sim's upper limit
inline constexpr double kFinestCountM = 1.0 / kFinestCountsPerMeter;
inline constexpr double kGraspStartM = 0.001;  ///< handle and set-point, 1 mm inside the wall
inline constexpr double kGraspDurationS = 40.0;
inline constexpr double kNyquistFitFromS = 8.0;
inline constexpr double kNyquistWindowS = 0.1;
inline constexpr double kNyquistTolerance = 0.005;  ///< relative, on the rate

inline tune::OperatorModel issue_grasp() {
    return tune::OperatorModel::two_mass_grasp(kSkinStiffnessNPerM, 0.0, kGraspHandMassKg,
                                               kArmStiffnessNPerM, 0.0);
}

inline std::string issue_grasp_human() {
    return "model = \"two-mass-grasp\"\nhand_mass = " + toml_number(kGraspHandMassKg) +
           "\nskin_stiffness = " + toml_number(kSkinStiffnessNPerM) +
           "\nskin_damping = 0.0\narm_stiffness = " + toml_number(kArmStiffnessNPerM) +
           "\narm_damping = 0.0\n";
}

inline std::string grasp_config(const CouplingGains& gains, std::string_view check) {
    DaemonConfig config;
    config.coupling = coupling_table(gains, check);
    config.counts_per_meter = kFinestCountsPerMeter;
    config.initial_position = toml_number(kGraspStartM);  // the set-point too (its default)
    config.humans = human_table(issue_grasp_human());
    config.soft_start_ramp_s = 0.0;  // the force's step rings the grasp's modes
    return config.toml();
}

/// The start-up check's line in hapticd's messages: "... worst margin M at F Hz".
struct CheckLine {
    std::string line;
    double margin = 0.0;
    double frequency_hz = -1.0;
};

/// The first line of `messages` that contains `marker`, with its margin and frequency.
inline std::optional<CheckLine> find_check_line(const std::string& messages,
                                                std::string_view marker) {
    static const std::regex margin_at(R"(worst margin (\S+) at (\S+) Hz)");
    std::size_t begin = 0;
    while (begin < messages.size()) {
        std::size_t end = messages.find('\n', begin);
        if (end == std::string::npos) end = messages.size();
        const std::string line = messages.substr(begin, end - begin);
        std::smatch match;
        if (line.find(marker) != std::string::npos && std::regex_search(line, match, margin_at)) {
            return CheckLine{line, std::stod(match[1].str()), std::stod(match[2].str())};
        }
        begin = end + 1;
    }
    return std::nullopt;
}

/// The fit of the alternating component over the linear phase.
struct NyquistFit {
    double growth_per_s = 0.0;  ///< of the alternating component's RMS
    std::size_t windows = 0;
    double first_rms_m = 0.0, last_rms_m = 0.0;  ///< of the fitted windows
    bool alternates = true;  ///< y[n] kept its sign over the fit: x alternates every tick
};

/// Checks the grasp's run (exit 0, no fault, every tick, no saturation, the solve converged,
/// the tool in the wall all along: the loop stayed linear) and fits its alternating component.
inline NyquistFit fit_nyquist_growth(const DaemonRun& run, const std::string& label) {
    NyquistFit out;
    EXPECT_EQ(run.exit_code, 0) << label << "\n" << run.err;
    EXPECT_EQ(fault_list(run), "") << label;
    EXPECT_EQ(run.log.rows(), static_cast<std::size_t>(kGraspDurationS * kRateHz)) << label;
    if (run.log.rows() == 0) return out;
    EXPECT_EQ(run.summary.at("saturated_ticks").get<double>(), 0.0) << label;
    EXPECT_EQ(run.summary.at("solver_not_converged").get<double>(), 0.0) << label;
    const auto& x = run.log.column("x0_m");
    const auto& xe = run.log.column("xe0_m");
    // The alternating component, demodulated from z = -1.
    std::vector<double> y(x.size(), 0.0);
    for (std::size_t n = 1; n < x.size(); ++n) {
        y[n] = (n % 2 == 0 ? 0.5 : -0.5) * (x[n] - x[n - 1]);
    }
    // RMS per window, from kNyquistFitFromS until it falls to 100 encoder counts.
    const auto window = static_cast<std::size_t>(std::lround(kNyquistWindowS * kRateHz));
    const auto first = static_cast<std::size_t>(kNyquistFitFromS * kRateHz);
    const double sign = y[first] > 0.0 ? 1.0 : -1.0;
    std::vector<double> mid_s, log_rms;
    for (std::size_t begin = first; begin + window <= y.size(); begin += window) {
        double sum = 0.0;
        bool same_sign = true;
        for (std::size_t n = begin; n < begin + window; ++n) {
            sum += y[n] * y[n];
            same_sign = same_sign && sign * y[n] > 0.0;
        }
        const double rms = std::sqrt(sum / static_cast<double>(window));
        if (rms <= 100.0 * kFinestCountM) break;
        out.alternates = out.alternates && same_sign;
        mid_s.push_back((static_cast<double>(begin) + 0.5 * static_cast<double>(window)) *
                        kPeriodS);
        log_rms.push_back(std::log(rms));
    }
    out.windows = mid_s.size();
    if (out.windows >= 2) {
        out.growth_per_s = tune::least_squares_slope(mid_s, log_rms, 0, out.windows);
        out.first_rms_m = std::exp(log_rms.front());
        out.last_rms_m = std::exp(log_rms.back());
    }
    // The linear loop needs the tool in the wall all along.
    for (std::size_t n = 0; n < xe.size(); ++n) {
        EXPECT_GT(xe[n], 0.0) << label << ": the tool left the wall at tick " << n;
        if (xe[n] <= 0.0) break;
    }
    return out;
}

/// The fit grows (or decays) at the exact model's rate, at Nyquist, alternating every tick.
inline void expect_nyquist_rate_as_predicted(const NyquistFit& fit, double predicted_frequency_hz,
                                             double predicted_growth_per_s) {
    EXPECT_NEAR(predicted_frequency_hz, 0.5 * kRateHz, 1e-6);
    EXPECT_TRUE(fit.alternates) << "the samples did not alternate every tick";
    EXPECT_NEAR(fit.growth_per_s, predicted_growth_per_s,
                kNyquistTolerance * std::abs(predicted_growth_per_s));
}

}  // namespace hapticd::testing
