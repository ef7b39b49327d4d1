// The fit chart of haptic-tune identify (--chart): for each identified axis, the velocity
// the log measured against the velocity the identified model predicts when it runs free
// under the logged force from the log's first velocity (tune::free_run_positions). Nothing
// is refitted along the way, so the chart shows simulation error: a model that is right
// tracks the measurement for the whole log; one that is wrong drifts off at once.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "hapticd/tune/identification.hpp"

namespace hapticd::tools {

/// How well the model's free run follows the measured velocity of one axis.
struct FreeRunFit {
    double velocity_rms_error_mps = 0.0;
    /// 1 - Σ error² / Σ (v - mean v)²: the share of the velocity's variance the model
    /// explains (1: all of it).
    double explained_fraction = 0.0;
};

/// The "identify-fit" chart's data for `axes` of `log` (read with every column identify
/// needs); `fits` receives each axis' numbers, in the order of `axes`.
nlohmann::ordered_json identify_fit_chart(const tune::TelemetryLog& log,
                                          const std::vector<tune::IdentifiedAxis>& axes,
                                          std::vector<FreeRunFit>& fits);

}  // namespace hapticd::tools
