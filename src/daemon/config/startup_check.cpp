#include "hapticd/daemon/startup_check.hpp"

#include <functional>
#include <sstream>

namespace hapticd::daemon {

std::string StartupCheck::model_name() const {
    return skipped ? skipped_model : std::string(tune::to_string(model));
}

std::string StartupCheck::describe() const {
    if (skipped) {
        return "stability check OFF ([coupling] check = \"off\"): these gains are not checked "
               "against any model";
    }
    return StabilityVerdict::describe();
}

tune::EnvironmentAssumption scene_environments(const env::Scene& scene,
                                               const std::string& scene_source) {
    const std::string where = scene_source + " (scene \"" + scene.name + "\")";
    if (!scene.unmodelled.empty()) {
        throw ConfigError(where +
                          " cannot be checked against its own objects: " + scene.unmodelled +
                          "; check against every passive environment instead ([coupling] "
                          "environments = \"every-passive\", the default; haptic-tune without "
                          "--scene)");
    }
    if (scene.linear_objects.empty()) {
        throw ConfigError(where +
                          " has no objects: in free space the coupling carries no force, so "
                          "a check against the scene's objects has nothing to check; check "
                          "against every passive environment instead");
    }
    tune::EnvironmentAssumption out;
    out.scene_name = scene_source;
    for (const env::LinearObject& o : scene.linear_objects) {
        out.scene.push_back({o.rigid ? tune::EnvironmentModel::rigid_wall()
                                     : tune::EnvironmentModel::mass_spring(
                                           o.mass_kg, o.stiffness_n_per_m, o.damping_n_s_per_m),
                             o.source});
    }
    return out;
}

void require_device_model(const Config& config) {
    if (!config.device.model.mass_kg || !config.device.model.damping_n_s_per_m) {
        throw ConfigError(config.source +
                          ": [device.model] mass and damping are required: the start-up "
                          "stability check sizes nothing without them (measure them with "
                          "haptic-tune identify)");
    }
}

namespace {

tune::EnvironmentAssumption configured_environments(const Config& config) {
    if (config.coupling.environments != EnvironmentClass::scene) return {};
    if (config.scene_file.empty()) {
        return scene_environments(
            env::parse_scene(default_scene_text(), "<embedded demo-wall scene>",
                             config.device.axes),
            "<embedded demo-wall scene>");
    }
    return scene_environments(
        env::load_scene(config.scene_file, config.device.axes, {.rate_hz = config.servo.rate_hz}),
        config.scene_file);
}

// Everything of the design but the environments, checked in this order.
tune::StabilityDesign design_but_environments(const Config& config) {
    if (!config.coupling.check) {
        throw ConfigError(config.source +
                          ": [coupling] check = \"off\": the config asks for no stability "
                          "check; name a model to check these gains with");
    }
    require_device_model(config);
    tune::StabilityDesign design;
    design.device = {*config.device.model.mass_kg, *config.device.model.damping_n_s_per_m};
    design.coupling = {config.coupling.stiffness_n_per_m, config.coupling.damping_n_s_per_m,
                       config.coupling.velocity_filter_hz};
    if (design.coupling.renders_nothing()) {
        throw ConfigError(config.source +
                          ": [coupling] stiffness and damping are both 0: no coupling to "
                          "render with (size one with haptic-tune size)");
    }
    design.rate_hz = config.servo.rate_hz;
    design.delay_s = config.device.model.delay_s;
    design.model = *config.coupling.check;
    design.assumption.operators = config.operators;
    return design;
}

// check = "off" skips it; else the design with `environments()` (read after the rest of the
// design is checked, so that its errors come first, as they always have).
StartupCheck check_design(const Config& config,
                          const std::function<tune::EnvironmentAssumption()>& environments) {
    StartupCheck check;
    if (!config.coupling.check) {
        check.skipped = true;
        check.passed = true;
        return check;
    }
    tune::StabilityDesign design = design_but_environments(config);
    design.assumption.environments = environments();
    static_cast<tune::StabilityVerdict&>(check) = tune::check_stability(design);
    return check;
}

}  // namespace

tune::StabilityDesign stability_design(const Config& config) {
    tune::StabilityDesign design = design_but_environments(config);
    design.assumption.environments = configured_environments(config);
    return design;
}

StartupCheck check_coupling_at_startup(const Config& config) {
    return check_design(config, [&config] { return configured_environments(config); });
}

StartupCheck check_coupling_at_startup(const Config& config, const env::Scene& scene,
                                       const std::string& scene_source) {
    return check_design(config, [&] {
        return config.coupling.environments == EnvironmentClass::scene
                   ? scene_environments(scene, scene_source)
                   : tune::EnvironmentAssumption{};
    });
}

}  // namespace hapticd::daemon
