// haptic-tune size: the largest coupling stiffness (and optionally the best damping) that
// keeps the interface unconditionally stable, from (21) or, for an admittance display, (37).
#include <cmath>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/exact_model.hpp"

namespace hapticd::tools {
namespace {

struct SizeOptions {
    DeviceOptions device;
    std::optional<double> coupling_damping;
    bool optimize_damping = false;
    std::string model;
    std::string display = "impedance";
    std::optional<double> kp;
    std::optional<double> ki;
    bool json = false;
    bool skip_exact_check = false;
};

nlohmann::ordered_json report_fields(const tune::SizingReport& report) {
    return {{"method", report.method},
            {"ceres_iterations", report.ceres_iterations},
            {"verify_points", report.verify_points},
            {"solver_time_s", report.solver_time_s}};
}

/// The sized design held against the exact sampled-data model, the ground truth the
/// frequency-domain models approximate. Warns on stderr when it disagrees.
nlohmann::ordered_json exact_cross_check(const DesignInput& input,
                                         const theory::SpringDamperCoupling& coupling,
                                         bool* stable) {
    const tune::ExactCheck exact =
        tune::check_exact(input.device, coupling, input.rate_hz, input.delay_periods());
    *stable = exact.stable;
    if (!exact.stable) {
        std::cerr << "haptic-tune: the exact sampled-data model finds this design unstable: "
                  << exact.worst_operator.describe() << " against "
                  << exact.worst_environment.describe()
                  << " grows by |z| = " << exact.worst_spectral_radius << " per tick at "
                  << exact.worst_frequency_hz
                  << " Hz. Only the passive model (the default) holds for every passive "
                     "operator (docs/stability-models.md); exit 1.\n";
    }
    return {{"stable", exact.stable},
            {"worst_spectral_radius", exact.worst_spectral_radius},
            {"worst_frequency_hz", exact.worst_frequency_hz},
            {"worst_operator", exact.worst_operator.describe()},
            {"worst_environment", exact.worst_environment.describe()},
            {"cases_checked", exact.cases_checked}};
}

int run_impedance(const SizeOptions& o, const DesignInput& input, theory::HoldModel model) {
    tune::ImpedanceSizingRequest request;
    request.device = input.device;
    request.rate_hz = input.rate_hz;
    request.model = {model, input.delay_periods()};
    request.velocity_filter_hz = input.velocity_filter_hz;
    request.coupling_damping_n_s_per_m = o.optimize_damping
                                             ? std::nullopt
                                             : std::optional<double>(o.coupling_damping.value_or(
                                                   input.coupling_damping_n_s_per_m.value_or(0.0)));
    const tune::ImpedanceSizing sizing = tune::size_impedance_coupling(request);
    nlohmann::ordered_json out = {
        {"display", "impedance"},
        {"stiffness", sizing.coupling.stiffness_n_per_m},
        {"damping", sizing.coupling.damping_n_s_per_m},
        {"velocity_filter_hz", sizing.coupling.velocity_filter_hz},
        {"binding_frequency_hz", sizing.binding_frequency_hz},
        {"model", std::string(theory::to_string(model))},
        {"delay_s", input.delay_s},
        {"delay_periods", input.delay_periods()},
        {"solver_time_s", sizing.report.solver_time_s},
        {"verified_worst_margin", sizing.verified_worst_margin},
        {"device", {{"mass", input.device.mass_kg}, {"damping", input.device.damping_n_s_per_m}}},
        {"rate_hz", input.rate_hz},
        {"solver", report_fields(sizing.report)},
    };
    bool stable = true;
    if (!o.skip_exact_check)
        out["exact_check"] = exact_cross_check(input, sizing.coupling, &stable);
    print_result(out, o.json);
    return stable ? kExitOk : kExitVerdictNo;
}

int run_admittance(const SizeOptions& o, const DesignInput& input, theory::HoldModel model) {
    if (!o.kp || !o.ki) {
        throw UsageError("--display admittance needs the PI velocity-loop gains --kp and --ki");
    }
    tune::AdmittanceSizingRequest request;
    request.device = input.device;
    request.loop = {*o.kp, *o.ki};
    request.rate_hz = input.rate_hz;
    request.model = model;
    if (!o.optimize_damping) {
        request.coupling_damping_n_s_per_m =
            o.coupling_damping.value_or(std::numeric_limits<double>::infinity());
    }
    const tune::AdmittanceSizing sizing = tune::size_admittance_coupling(request);
    const double b_c = sizing.coupling.damping_n_s_per_m;
    nlohmann::ordered_json out = {
        {"display", "admittance"},
        {"coupling_mass", sizing.coupling.mass_kg},
        // null: no series damper (b_c = inf), the coupling is a pure mass.
        {"damping",
         std::isinf(b_c) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(b_c)},
        {"binding_frequency_hz", sizing.binding_frequency_hz},
        {"model", std::string(theory::to_string(model))},
        {"solver_time_s", sizing.report.solver_time_s},
        {"verified_worst_margin", sizing.verified_worst_margin},
        {"device", {{"mass", input.device.mass_kg}, {"damping", input.device.damping_n_s_per_m}}},
        {"pi_gains", {{"kp", *o.kp}, {"ki", *o.ki}}},
        {"rate_hz", input.rate_hz},
        {"solver", report_fields(sizing.report)},
    };
    print_result(out, o.json);
    return kExitOk;
}

}  // namespace

void add_size_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<SizeOptions>();
    CLI::App* command = app.add_subcommand(
        "size",
        "Largest coupling stiffness k_c (impedance display) or smallest coupling mass m_c "
        "(admittance display) for which the interface is unconditionally stable");
    add_device_options(*command, options->device);
    add_delay_option(*command, options->device);
    add_velocity_filter_option(*command, options->device);
    CLI::Option* damping =
        command
            ->add_option("--coupling-damping", options->coupling_damping,
                         "coupling damping b_c (N s/m); impedance default 0, admittance "
                         "default none (pure mass)")
            ->check(non_negative_finite("N s/m"));
    command
        ->add_flag("--optimize-damping", options->optimize_damping,
                   "find the best (k_c, b_c) pair instead of k_c for a given b_c")
        ->excludes(damping);
    add_model_option(*command, options->model, {"passive", "paper", "encoder"});
    command->add_option("--display", options->display, "display causality (default impedance)")
        ->check(CLI::IsMember({"impedance", "admittance"}));
    command->add_option("--kp", options->kp, "admittance display: PI proportional gain (N s/m)")
        ->check(non_negative_finite("N s/m"));
    command->add_option("--ki", options->ki, "admittance display: PI integral gain (N/m)")
        ->check(non_negative_finite("N/m"));
    command->add_flag("--json", options->json, "print the result as JSON");
    command->add_flag("--no-exact-check", options->skip_exact_check,
                      "impedance display: skip holding the answer against the exact model");
    CLI::Option* model_option = command->get_option("--model");
    command->callback([options, model_option, &invocation] {
        // The admittance display has no passive model yet: its default is encoder.
        if (options->display == "admittance" && model_option->count() == 0)
            options->model = "encoder";
        invocation.run = [options] {
            const DesignInput input = resolve_design_input(options->device);
            const theory::HoldModel model = *theory::parse_hold_model(options->model);
            if (options->display == "admittance") {
                if (input.velocity_filter_hz != 0.0) {
                    throw UsageError(
                        "--velocity-filter is the impedance display's coupling damper; the "
                        "admittance display's coupling (32) has none");
                }
                if (model == theory::HoldModel::passive || input.delay_s != 0.0) {
                    throw UsageError(
                        "--display admittance is sized from (37) with --model encoder or paper "
                        "and no loop delay (pass --delay 0 over a config's [device.model] delay): "
                        "the passive model of the admittance display is not built yet "
                        "(docs/stability-models.md)");
                }
                return run_admittance(*options, input, model);
            }
            return run_impedance(*options, input, model);
        };
    });
}

}  // namespace hapticd::tools
