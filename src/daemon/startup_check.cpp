#include "hapticd/daemon/startup_check.hpp"

#include <sstream>

#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/class_check.hpp"

namespace hapticd::daemon {

std::string StartupCheck::describe() const {
    std::ostringstream out;
    if (skipped) {
        return "stability check OFF ([coupling] check = \"off\"): these gains are not checked "
               "against any model";
    }
    out << "stability check (" << model << " model, loop delay " << delay_s * 1e3 << " ms";
    if (velocity_filter_hz > 0.0) out << ", velocity filter " << velocity_filter_hz << " Hz";
    out << "): " << (passed ? "unconditionally stable" : "NOT unconditionally stable")
        << ", worst margin " << worst_margin << " at " << worst_frequency_hz << " Hz";
    if (!worst_case.empty()) out << " (" << worst_case << ")";
    if (guarantee) {
        out << "; holds for " << holds_for;
        if (model == "exact") out << ", as far as the exact model's search reaches";
    } else {
        out << ". The " << model
            << " model is NOT a guarantee: it keeps one term of the hold's alias sum and "
               "misses operators with several modes (docs/stability-models.md); use check = "
               "\"passive\" (the default) or \"exact\" to arm hardware";
    }
    return out.str();
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

namespace {

tune::EnvironmentAssumption configured_environments(const Config& config) {
    if (config.coupling.environments != "scene") return {};
    try {
        if (config.scene_file.empty()) {
            return scene_environments(
                env::parse_scene(default_scene_text(), "<embedded demo-wall scene>",
                                 config.device.axes),
                "<embedded demo-wall scene>");
        }
        return scene_environments(env::load_scene(config.scene_file, config.device.axes),
                                  config.scene_file);
    } catch (const env::SceneError& e) {
        throw ConfigError(e.what());
    }
}

}  // namespace

StartupCheck check_coupling_at_startup(const Config& config) {
    if (config.coupling.check == "off") {
        StartupCheck skipped;
        skipped.model = "off";
        skipped.skipped = true;
        skipped.passed = true;
        return skipped;
    }
    if (!config.device.model_mass_kg || !config.device.model_damping_n_s_per_m) {
        throw ConfigError(config.source +
                          ": [device.model] mass and damping are required: the start-up "
                          "stability check sizes nothing without them (measure them with "
                          "haptic-tune identify)");
    }
    const theory::DeviceModel device{*config.device.model_mass_kg,
                                     *config.device.model_damping_n_s_per_m};
    const theory::SpringDamperCoupling coupling{config.coupling.stiffness_n_per_m,
                                                config.coupling.damping_n_s_per_m,
                                                config.coupling.velocity_filter_hz};
    if (coupling.stiffness_n_per_m == 0.0 && coupling.damping_n_s_per_m == 0.0) {
        throw ConfigError(config.source +
                          ": [coupling] stiffness and damping are both 0: no coupling to "
                          "render with (size one with haptic-tune size)");
    }
    StartupCheck check;
    check.model = config.coupling.check;
    check.delay_s = config.device.model_delay_s;
    check.velocity_filter_hz = coupling.velocity_filter_hz;
    const double delay_periods = config.device.model_delay_s * config.servo.rate_hz;
    const tune::StabilityAssumption assumption{config.operators, configured_environments(config)};
    check.holds_for = assumption.describe();
    if (check.model == "exact") {
        const tune::ExactCheck exact =
            tune::check_exact(device, coupling, config.servo.rate_hz, assumption, delay_periods);
        check.passed = exact.stable;
        check.worst_margin = exact.worst_margin;
        check.worst_frequency_hz = exact.worst_frequency_hz;
        check.worst_case =
            exact.worst_operator.describe() + " against " + exact.worst_environment.describe();
        return check;
    }
    const theory::HoldModel model = *theory::parse_hold_model(check.model);
    check.guarantee = model == theory::HoldModel::passive;
    if (!assumption.environments.every_passive()) {
        const tune::SceneCheck scene = tune::check_passive_scene(
            device, coupling, config.servo.rate_hz, assumption.environments.scene, delay_periods);
        check.passed = scene.stable;
        check.worst_margin = scene.margin;
        check.worst_frequency_hz = scene.worst_frequency_hz;
        check.worst_case = scene.worst_environment;
        return check;
    }
    const theory::CouplingCheck result =
        theory::check_coupling(device, coupling, {model, delay_periods}, config.servo.rate_hz);
    check.passed = result.unconditionally_stable;
    check.worst_margin = result.worst_margin;
    check.worst_frequency_hz = result.worst_frequency_hz;
    return check;
}

}  // namespace hapticd::daemon
