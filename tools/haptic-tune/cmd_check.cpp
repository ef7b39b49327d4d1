// haptic-tune check: is a design unconditionally stable under a stability model?
// Exit 0 when it is, 1 when it is not.
#include <memory>

#include "assumption_options.hpp"
#include "commands.hpp"
#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::tools {
namespace {

struct CheckOptions {
    DeviceOptions device;
    std::optional<double> stiffness;
    std::optional<double> coupling_damping;
    std::string model;
    AssumptionOptions assumption;
    bool json = false;
};

/// What a verdict rests on: the class of operators and environments it holds for.
std::string holds_for(const std::string& model, const tune::StabilityAssumption& assumption) {
    if (model == "passive") {
        return assumption.describe() +
               " (Colgate and Schenkel's sampled-data passivity condition at the device port)";
    }
    if (model == "exact") {
        return assumption.describe() +
               ", as far as the exact model's search reaches (its sweep, its synthesised "
               "adversaries: multi-mode operators on the aliases and worst lossless "
               "environments" +
               (assumption.operators ? std::string(", and the search of the class)") : ")");
    }
    return "no class: the " + model +
           " model keeps one term of the hold's alias sum and is not a guarantee "
           "(docs/stability-models.md)";
}

int run_check(const CheckOptions& o) {
    const DesignInput input = resolve_design_input(o.device);
    theory::SpringDamperCoupling coupling;
    if (o.stiffness) {
        coupling.stiffness_n_per_m = *o.stiffness;
    } else if (input.coupling_stiffness_n_per_m) {
        coupling.stiffness_n_per_m = *input.coupling_stiffness_n_per_m;
    } else {
        throw UsageError("missing --stiffness (or [coupling] stiffness in --config)");
    }
    coupling.damping_n_s_per_m =
        o.coupling_damping.value_or(input.coupling_damping_n_s_per_m.value_or(0.0));
    coupling.velocity_filter_hz = input.velocity_filter_hz;
    if (coupling.stiffness_n_per_m == 0.0 && coupling.damping_n_s_per_m == 0.0) {
        throw UsageError("--stiffness 0 with --coupling-damping 0 is no coupling at all");
    }
    tune::check_coupling_gains(coupling);
    const tune::StabilityAssumption assumption = resolve_assumption(o.assumption, o.model);

    nlohmann::ordered_json out;
    bool stable = false;
    if (o.model == "exact") {
        const tune::ExactCheck exact = tune::check_exact(input.device, coupling, input.rate_hz,
                                                         assumption, input.delay_periods());
        stable = exact.stable;
        out = {{"unconditionally_stable", exact.stable},
               {"worst_margin", exact.worst_margin},
               {"worst_frequency_hz", exact.worst_frequency_hz},
               {"model", "exact"},
               {"worst_operator", exact.worst_operator.describe()},
               {"worst_environment", exact.worst_environment.describe()},
               {"worst_spectral_radius", exact.worst_spectral_radius},
               {"cases_checked", exact.cases_checked}};
    } else if (!assumption.environments.every_passive()) {
        const tune::SceneCheck scene =
            tune::check_passive_scene(input.device, coupling, input.rate_hz,
                                      assumption.environments.scene, input.delay_periods());
        stable = scene.stable;
        out = {{"unconditionally_stable", scene.stable},
               {"worst_margin", scene.margin},
               {"worst_frequency_hz", scene.worst_frequency_hz},
               {"model", o.model},
               {"worst_environment", scene.worst_environment},
               {"damping_needed", scene.damping_needed}};
    } else {
        const theory::HoldModel model = *theory::parse_hold_model(o.model);
        const theory::CouplingCheck check = theory::check_coupling(
            input.device, coupling, {model, input.delay_periods()}, input.rate_hz);
        stable = check.unconditionally_stable;
        out = {{"unconditionally_stable", check.unconditionally_stable},
               {"worst_margin", check.worst_margin},
               {"worst_frequency_hz", check.worst_frequency_hz},
               {"model", o.model}};
    }
    out["holds_for"] = holds_for(o.model, assumption);
    out["delay_s"] = input.delay_s;
    out["delay_periods"] = input.delay_periods();
    out["stiffness"] = coupling.stiffness_n_per_m;
    out["damping"] = coupling.damping_n_s_per_m;
    out["velocity_filter_hz"] = coupling.velocity_filter_hz;
    out["device"] = {{"mass", input.device.mass_kg}, {"damping", input.device.damping_n_s_per_m}};
    out["rate_hz"] = input.rate_hz;
    print_result(out, o.json);
    return stable ? kExitOk : kExitVerdictNo;
}

}  // namespace

void add_check_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<CheckOptions>();
    CLI::App* command = app.add_subcommand(
        "check", "Check a coupling design; exit 0 if unconditionally stable, 1 if not");
    add_device_options(*command, options->device);
    add_delay_option(*command, options->device);
    add_velocity_filter_option(*command, options->device);
    command->add_option("--stiffness", options->stiffness, "coupling stiffness k_c (N/m)")
        ->check(non_negative_finite("N/m"));
    command
        ->add_option("--coupling-damping", options->coupling_damping,
                     "coupling damping b_c (N s/m), default 0")
        ->check(non_negative_finite("N s/m"));
    add_model_option(*command, options->model, {"passive", "exact", "paper", "encoder"});
    add_assumption_options(*command, options->assumption);
    command->add_flag("--json", options->json, "print the result as JSON");
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_check(*options); }; });
}

}  // namespace hapticd::tools
