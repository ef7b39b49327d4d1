// haptic-tune check: is a design unconditionally stable under a stability model? The same
// function as hapticd's start-up check (tune::check_stability), on the same design: a
// --config is read exactly as hapticd reads it, model and assumptions included
// (daemon::stability_design), and flags override it. Exit 0 when it is stable, 1 when not.
#include <memory>

#include "assumption_options.hpp"
#include "commands.hpp"
#include "hapticd/daemon/startup_check.hpp"
#include "hapticd/tune/result_json.hpp"
#include "hapticd/tune/stability_check.hpp"

namespace hapticd::tools {
namespace {

struct CheckOptions {
    DeviceOptions device;
    std::optional<double> stiffness;
    std::optional<double> coupling_damping;
    std::string model;
    bool model_given = false;  ///< --model was on the command line
    AssumptionOptions assumption;
    bool json = false;
};

/// What a verdict rests on: the class of operators and environments it holds for, and how.
std::string holds_for(const tune::StabilityVerdict& verdict, const tune::StabilityDesign& design) {
    if (verdict.model == tune::StabilityModel::passive) {
        return verdict.holds_for +
               " (Colgate and Schenkel's sampled-data passivity condition at the device port)";
    }
    if (verdict.model == tune::StabilityModel::exact) {
        return verdict.holds_for +
               (verdict.proven ? ", proven by " + verdict.proof : std::string(", not proven")) +
               "; the exact model's search (its sweep, its synthesised adversaries: multi-mode "
               "operators on the aliases and worst lossless environments" +
               (design.assumption.operators ? std::string(", and the search of the class") : "") +
               ") looks for an operator that breaks it";
    }
    return "no class: the " + std::string(tune::to_string(verdict.model)) +
           " model keeps one term of the hold's alias sum and is not a guarantee "
           "(docs/stability-models.md)";
}

/// The design: the config as hapticd reads it, with the flags over it, or the flags alone.
tune::StabilityDesign design_of(const CheckOptions& o) {
    const DesignInput input = resolve_design_input(o.device);
    daemon::Config config = input.config ? *input.config : daemon::Config{};
    if (!input.config) config.source = "the command line";
    config.device.model.mass_kg = input.device.mass_kg;
    config.device.model.damping_n_s_per_m = input.device.damping_n_s_per_m;
    config.servo.rate_hz = input.rate_hz;
    config.device.model.delay_s = input.delay_s;
    config.coupling.velocity_filter_hz = input.velocity_filter_hz;
    if (o.stiffness) {
        config.coupling.stiffness_n_per_m = *o.stiffness;
    } else if (!input.config) {
        throw UsageError("missing --stiffness (or [coupling] stiffness in --config)");
    }
    if (o.coupling_damping) config.coupling.damping_n_s_per_m = *o.coupling_damping;
    if ((o.stiffness || o.coupling_damping) && config.coupling.stiffness_n_per_m == 0.0 &&
        config.coupling.damping_n_s_per_m == 0.0) {
        throw UsageError("--stiffness 0 with --coupling-damping 0 is no coupling at all");
    }
    // The model: --model, else the config's [coupling] check, else passive.
    if (o.model_given || !input.config) {
        config.coupling.check = tune::parse_stability_model(o.model);
    } else if (!config.coupling.check) {
        throw UsageError(config.source +
                         ": [coupling] check = \"off\": hapticd checks nothing; give --model "
                         "to check these gains");
    }
    const tune::StabilityModel model = *config.coupling.check;
    // What the chosen model cannot use of the config's assumptions goes (the passive model
    // holds for every operator, paper and encoder for no class), and the flags replace it.
    if (model != tune::StabilityModel::exact) config.operators.reset();
    if (!tune::is_guarantee(model) || !o.assumption.scene_path.empty()) {
        config.coupling.environments = daemon::EnvironmentClass::every_passive;
    }
    tune::StabilityDesign design = daemon::stability_design(config);
    const tune::StabilityAssumption flags =
        resolve_assumption(o.assumption, std::string(tune::to_string(model)));
    if (flags.operators) design.assumption.operators = flags.operators;
    if (!flags.environments.every_passive()) design.assumption.environments = flags.environments;
    return design;
}

int run_check(const CheckOptions& o) {
    const tune::StabilityDesign design = design_of(o);
    const tune::StabilityVerdict verdict = tune::check_stability(design);
    nlohmann::ordered_json out = verdict;
    out["holds_for"] = holds_for(verdict, design);
    out["delay_periods"] = design.delay_s * design.rate_hz;
    out["stiffness"] = design.coupling.stiffness_n_per_m;
    out["damping"] = design.coupling.damping_n_s_per_m;
    out["device"] = design.device;
    out["rate_hz"] = design.rate_hz;
    print_result(out, o.json);
    return verdict.passed ? kExitOk : kExitVerdictNo;
}

}  // namespace

void add_check_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<CheckOptions>();
    CLI::App* command = app.add_subcommand(
        "check",
        "Check a coupling design; exit 0 if unconditionally stable, 1 if not. With --config: "
        "the design and the verdict of hapticd's start-up check for that config");
    add_device_options(*command, options->device);
    add_delay_option(*command, options->device);
    add_velocity_filter_option(*command, options->device);
    command->add_option("--stiffness", options->stiffness, "coupling stiffness k_c (N/m)")
        ->check(non_negative_finite("N/m"));
    command
        ->add_option("--coupling-damping", options->coupling_damping,
                     "coupling damping b_c (N s/m), default 0")
        ->check(non_negative_finite("N s/m"));
    CLI::Option* model =
        add_model_option(*command, options->model, {"passive", "exact", "paper", "encoder"});
    add_assumption_options(*command, options->assumption);
    command->add_flag("--json", options->json, "print the result as JSON");
    command->callback([options, model, &invocation] {
        options->model_given = model->count() > 0;
        invocation.run = [options] { return run_check(*options); };
    });
}

}  // namespace hapticd::tools
