// The start-up stability check (DESIGN.md, Safety model): hapticd refuses to arm with
// coupling gains that fail the configured stability model ([coupling] check) for the
// configured device model ([device.model]) at [servo] rate_hz.
#pragma once

#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/tune/environment_assumption.hpp"

namespace hapticd::daemon {

struct StartupCheck {
    bool passed = false;
    bool skipped = false;  ///< check = "off": nothing was checked
    std::string model;     ///< "passive", "exact", "paper" or "encoder"
    /// passive and exact hold for every passive operator; paper and encoder do not.
    bool guarantee = true;
    double delay_s = 0.0;             ///< the loop delay the check assumed ([device.model] delay)
    double velocity_filter_hz = 0.0;  ///< [coupling] velocity_filter, in Z_c of every model
    double worst_margin = 0.0;
    double worst_frequency_hz = 0.0;
    std::string worst_case;  ///< exact model: the operator and environment
    /// The class of operators and environments the verdict rests on.
    std::string holds_for;
    /// One line for the log: the verdict, the margin and the frequency.
    std::string describe() const;
};

/// Runs the check. Throws ConfigError when [device.model] is missing or the gains are
/// zero, since there is then nothing to check against, and when [coupling] environments =
/// "scene" meets a scene without a linear model. With environments = "scene" it reads the
/// scene ([scene] file, or the embedded demo scene).
StartupCheck check_coupling_at_startup(const Config& config);

/// The scene's linearised objects as the environments a check holds for. Throws
/// ConfigError naming the scene and the object when it has no linear model or no objects.
tune::EnvironmentAssumption scene_environments(const env::Scene& scene,
                                               const std::string& scene_source);

}  // namespace hapticd::daemon
