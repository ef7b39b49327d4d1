// The start-up stability check (docs/architecture.md §7.9): hapticd refuses to arm with
// coupling gains that fail the configured stability model ([coupling] check) for the
// configured device model ([device.model]) at [servo] rate_hz.
#pragma once

#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/env/scene.hpp"
#include "hapticd/tune/environment_assumption.hpp"
#include "hapticd/tune/stability_check.hpp"

namespace hapticd::daemon {

/// The verdict of the start-up check: tune::check_stability()'s, the one haptic-tune check
/// gives for the same config, or nothing checked.
struct StartupCheck : tune::StabilityVerdict {
    bool skipped = false;  ///< nothing was checked: check = "off" (or an identify run)
    /// What the summary names as the model when skipped: "off", or why there is none.
    std::string skipped_model = "off";
    /// The summary's "model": the stability model's name, or skipped_model.
    std::string model_name() const;
    /// One line for the log: the verdict, the margin and the frequency (the verdict's
    /// describe()), or that nothing was checked.
    std::string describe() const;
};

/// What the start-up check checks: [device.model], the [coupling] gains and filter, [servo]
/// rate_hz, [device.model] delay, [coupling] check, and what the verdict holds for
/// ([operator]; [coupling] environments = "scene": the scene's own objects, from [scene]
/// file or the embedded demo scene). Throws ConfigError naming the file when
/// [device.model] is missing, the gains are both 0 (there is then nothing to check
/// against), check = "off", or the scene has no linear model.
tune::StabilityDesign stability_design(const Config& config);

/// Throws stability_design()'s ConfigError when [device.model] lacks mass or damping.
void require_device_model(const Config& config);

/// Runs the check: stability_design() and tune::check_stability(); check = "off" skips it.
/// Throws as stability_design() does, and std::invalid_argument from a model's own range
/// checks.
StartupCheck check_coupling_at_startup(const Config& config);
/// The same for `scene` (from `scene_source`) in place of [scene] file: a scene loaded over
/// the control socket, as built, not read again.
StartupCheck check_coupling_at_startup(const Config& config, const env::Scene& scene,
                                       const std::string& scene_source);

/// The scene's linearised objects as the environments a check holds for. Throws
/// ConfigError naming the scene and the object when it has no linear model or no objects.
tune::EnvironmentAssumption scene_environments(const env::Scene& scene,
                                               const std::string& scene_source);

}  // namespace hapticd::daemon
