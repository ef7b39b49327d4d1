// The wall-contact check that the daemon passes on the sim plugin (HilEncoderGains) and
// through every transport (UsbHilWallContact, HidClosedLoop, SerialDaemonContact), written
// once: each test builds its own rig (the sim plugin, or an emulated device behind libusb,
// hidapi or a pseudo-terminal), runs hapticd on the encoder model's gains against the stiff
// wall, and hands the run to expect_stable_wall_contact().
#pragma once

#include <gtest/gtest.h>

#include <iostream>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "hapticd_run.hpp"
#include "operators.hpp"
#include "pen_display.hpp"
#include "wall_contact.hpp"

namespace hapticd::testing {

/// The stiff wall every contact test presses, and where the handle starts.
inline constexpr double kContactWallStiffnessNPerM = 1e5;
inline constexpr double kContactStartM = -0.001;  ///< 1 mm in front of the wall

/// A contact run's operator: the test's parameter.
struct OperatorCase {
    std::string name;
    std::string human;  ///< the [device.sim.human] keys
};
inline void PrintTo(const OperatorCase& operator_case, std::ostream* out) {
    *out << operator_case.name;
}
inline std::string case_name(const ::testing::TestParamInfo<OperatorCase>& operator_case) {
    return operator_case.param.name;
}

/// A push of the operator's set-point `depth_m` into the wall from 1 s (after the soft
/// start's 0.2 s still and 0.5 s ramp), briskly (the handle meets the wall at ~0.1 m/s), and
/// held for longer than any run.
inline std::string push_into_wall(double depth_m) { return push_toml(depth_m, 1.0, 0.05, 100.0); }

/// The operators a transport is held to: nothing on the handle (the scene's 0.5 N preload
/// spring brings it in), and a 500 N/m grasp pushing 5 mm into the wall (about 2.3 N).
inline std::vector<OperatorCase> transport_operator_cases() {
    return {{"hands_off", hands_off()}, {"stiff_grasp", stiff_grasp(push_into_wall(0.005))}};
}

/// What a stable contact is, beyond the run itself.
struct ContactBounds {
    /// The contact was really excited before the judge looks: an impact, not a slow creep.
    double min_transient_m = 10.0 * kCountM;
};

/// The checks of a stable wall contact. The run: exit 0 on its duration, no fault, every tick
/// run and logged. The trajectory from `settle_s` on (judge_wall_contact): the oscillation
/// about the operating point does not grow, and what is left is the encoder's quantisation (a
/// few counts), not a limit cycle of the wall; the tool never left the wall; the force stayed
/// far from the limit, so the loop stayed linear. `label` starts the line it prints. None
/// (and a failure) when the run did not end well enough to be judged.
inline std::optional<ContactJudgement> expect_stable_wall_contact(
    const DaemonRun& run, double duration_s, double settle_s, const std::string& label,
    const ContactBounds& bounds = {}) {
    if (run.exit_code != 0 || !run.summary.is_object()) {
        ADD_FAILURE() << label << ": hapticd exited " << run.exit_code << ":\n" << run.err;
        return std::nullopt;
    }
    EXPECT_EQ(run.summary.at("exit"), "duration");
    EXPECT_EQ(fault_list(run), "");
    EXPECT_EQ(run.summary.at("ticks").get<double>(), duration_s * kRateHz);
    if (run.log.rows() != static_cast<std::size_t>(duration_s * kRateHz)) {
        ADD_FAILURE() << label << ": " << run.log.rows() << " rows logged, not "
                      << duration_s * kRateHz;
        return std::nullopt;
    }

    const ContactJudgement judged = judge_wall_contact(run.log, settle_s);
    std::cout << label << ": " << describe(judged) << "\n";
    EXPECT_GE(judged.transient_peak_m, bounds.min_transient_m) << "the contact was never excited";
    EXPECT_LE(judged.trend.growth_per_s, 0.1);
    EXPECT_LE(judged.trend.last_amplitude_m, 8.0 * kCountM);
    EXPECT_LE(judged.trend.peak_amplitude_m, 10.0 * kCountM);
    EXPECT_TRUE(judged.contact_kept()) << "left the wall at " << judged.contact_lost_at_s << " s";
    EXPECT_GT(judged.min_tool_depth_m, 0.0);
    EXPECT_LT(judged.max_abs_force_n, 0.5 * kForceLimitN);
    return judged;
}

}  // namespace hapticd::testing
