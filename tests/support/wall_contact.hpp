// The 1-axis contact experiment of the coupling tests (HilEncoderGains, HilPaperGains,
// HilNoCoupling): a stiff wall at x = 0 with free space at x < 0, and a weak preload.
//
// Scene: [[wall]] normal [-1], offset 0, stiffness K, damping B (it pushes only), plus a
// [[spring]] of 100 N/m anchored 5 mm inside the wall: 0.5 N toward the wall at its surface,
// "like gravity", so that an operator with no set-point of its own (hands-off, heavy hand)
// still comes to rest against the wall. With the coupling, (17), both act on the massless
// tool: its rest point is where the spring and the wall balance, 0.5 N / K inside the wall,
// and the handle rests there too. For small motions the handle feels k_c in series with K
// (+ 100 N/m); the tool stays in the wall while the handle's outward excursion is below
// 0.5 N / k_c, and beyond that the tool leaves it and the handle bounces (a limit cycle:
// the wall only pushes). Without the coupling the handle is the tool and rests 0.5 N / K
// inside the wall, with K (+ 100 N/m) acting on it directly.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

#include "hapticd/tune/oscillation.hpp"
#include "pen_display.hpp"
#include "telemetry_csv.hpp"

namespace hapticd::testing {

inline constexpr double kPreloadStiffnessNPerM = 100.0;
inline constexpr double kPreloadAnchorM = 0.005;  ///< 5 mm inside the wall: 0.5 N at x = 0
inline constexpr double kContactWindowS = 0.1;    ///< oscillation windows (>= 1.5 periods)

/// The wall (stiffness K, damping B) with the preload spring.
inline std::string wall_contact_scene(double wall_stiffness_n_per_m,
                                      double wall_damping_n_s_per_m = 0.0) {
    return "[scene]\nname = \"hil-wall-contact\"\naxes = 1\n"
           "[[wall]]\nnormal = [-1.0]\noffset = 0.0\nstiffness = " +
           toml_number(wall_stiffness_n_per_m) +
           "\ndamping = " + toml_number(wall_damping_n_s_per_m) + "\n[[spring]]\nanchor = [" +
           toml_number(kPreloadAnchorM) + "]\nstiffness = " + toml_number(kPreloadStiffnessNPerM) +
           "\n";
}

/// Dither of the handle up to this, peak to peak, is the encoder's quantisation: a
/// marginally damped loop (the encoder gains leave 4% of b) dithers by a few counts.
inline constexpr double kQuantisationFloorM = 3.0 * kCountM;

/// What the trajectory says about the contact from `settle_s` to the end of the log.
struct ContactJudgement {
    /// The handle position x0 in windows (0.1 s by default), each detrended: the oscillation
    /// about the operating point, never below kQuantisationFloorM.
    tune::OscillationTrend trend;
    /// When the tool first left the wall (xe0 < 0) after `settle_s`; < 0: it never did,
    /// i.e. contact was kept in every tick.
    double contact_lost_at_s = -1.0;
    /// The smallest depth of the tool in the wall after `settle_s`, min(xe0) (the wall is
    /// x > 0).
    double min_tool_depth_m = 0.0;
    /// The largest window amplitude before `settle_s`: how hard the contact was excited.
    double transient_peak_m = 0.0;
    double max_abs_force_n = 0.0;  ///< largest |f0| over the whole log

    bool contact_kept() const { return contact_lost_at_s < 0.0; }
    static double counts(double length_m) { return length_m / kCountM; }
};

/// `window_s`: the oscillation windows; at least 1.5 periods of the slowest oscillation.
inline ContactJudgement judge_wall_contact(const TelemetryLog& log, double settle_s,
                                           double window_s = kContactWindowS) {
    ContactJudgement judgement;
    const auto& t = log.column("t_s");
    const auto& x = log.column("x0_m");
    const auto& xe = log.column("xe0_m");
    const auto& f = log.column("f0_n");
    const auto first = static_cast<std::size_t>(
        std::lower_bound(t.begin(), t.end(), settle_s - 0.5 * kPeriodS) - t.begin());
    const auto window = static_cast<std::size_t>(std::lround(window_s / kPeriodS));
    judgement.trend = tune::oscillation_trend(x, kPeriodS, first, window, kQuantisationFloorM);
    const std::vector<double> before_settling(x.begin(),
                                              x.begin() + static_cast<std::ptrdiff_t>(first));
    judgement.transient_peak_m =
        tune::oscillation_trend(before_settling, kPeriodS, 0, window, kQuantisationFloorM)
            .peak_amplitude_m;

    judgement.min_tool_depth_m = first < xe.size() ? xe[first] : -1.0;
    for (std::size_t i = first; i < xe.size(); ++i) {
        judgement.min_tool_depth_m = std::min(judgement.min_tool_depth_m, xe[i]);
        if (xe[i] < 0.0 && judgement.contact_lost_at_s < 0.0) judgement.contact_lost_at_s = t[i];
    }
    for (const double force : f) {
        judgement.max_abs_force_n = std::max(judgement.max_abs_force_n, std::abs(force));
    }
    return judgement;
}

/// One line of the numbers, for the test's output and the report.
inline std::string describe(const ContactJudgement& j) {
    std::ostringstream out;
    out.precision(3);
    out << "growth " << j.trend.growth_per_s << " /s (rise " << j.trend.rise_growth_per_s
        << " /s); amplitude " << ContactJudgement::counts(j.trend.first_amplitude_m) << " -> peak "
        << ContactJudgement::counts(j.trend.peak_amplitude_m) << " -> last "
        << ContactJudgement::counts(j.trend.last_amplitude_m) << " counts p-p (transient "
        << ContactJudgement::counts(j.transient_peak_m) << "); contact "
        << (j.contact_kept() ? "kept" : "lost at " + std::to_string(j.contact_lost_at_s) + " s")
        << ", min tool depth " << j.min_tool_depth_m * 1e6 << " um; max |f| " << j.max_abs_force_n
        << " N";
    return out.str();
}

}  // namespace hapticd::testing
