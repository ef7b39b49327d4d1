#include "assumption_options.hpp"

#include "cli_common.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/env/scene.hpp"

namespace hapticd::tools {

void add_assumption_options(CLI::App& command, AssumptionOptions& options) {
    command.add_option("--operator-class", options.operator_class_path,
                       "a TOML file whose [operator] table declares the operator class "
                       "(hand_mass, grip_stiffness, grip_damping, arm_stiffness, arm_damping; "
                       "docs/stability-models.md); needs --model exact. Default: every passive "
                       "operator");
    command.add_option("--scene", options.scene_path,
                       "check against this scene's own linearised objects instead of every "
                       "passive environment (models passive and exact)");
}

tune::StabilityAssumption resolve_assumption(const AssumptionOptions& options,
                                             const std::string& model) {
    tune::StabilityAssumption assumption;
    if (!options.operator_class_path.empty()) {
        if (model != "exact") {
            throw UsageError("--operator-class needs --model exact: the " + model + " model " +
                             (model == "passive" ? "holds for every passive operator"
                                                 : "holds for no class of operators") +
                             ", so it cannot use a class");
        }
        assumption.operators = daemon::load_operator_class(options.operator_class_path);
    }
    if (!options.scene_path.empty()) {
        if (model != "passive" && model != "exact") {
            throw UsageError(
                "--scene needs --model passive or exact (the models that hold for "
                "a stated class of environments), not " +
                model);
        }
        // The scene's own axes: any count up to 3 is accepted here.
        assumption.environments =
            daemon::scene_environments(env::load_scene(options.scene_path, 3), options.scene_path);
    }
    return assumption;
}

}  // namespace hapticd::tools
