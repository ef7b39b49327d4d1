// haptic-tune size: the largest coupling stiffness (and optionally the best damping) that
// keeps the interface unconditionally stable, from (21) or, for an admittance display, (37).
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "assumption_options.hpp"
#include "commands.hpp"
#include "hapticd/theory/force_sensor_filter.hpp"
#include "hapticd/tune/admittance_sizing.hpp"
#include "hapticd/tune/class_proof.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/result_json.hpp"
#include "hapticd/tune/stability_check.hpp"

namespace hapticd::tools {
namespace {

struct SizeOptions {
    DeviceOptions device;
    std::optional<double> coupling_damping;
    bool optimize_damping = false;
    std::string model;
    DisplayOptions display;
    bool json = false;
    bool skip_exact_check = false;
    AssumptionOptions assumption;
    std::optional<double> force_filter_hz;
    double force_filter_damping = theory::ForceSensorFilter{}.damping_ratio;
    int force_filter_order = 2;
};

/// --force-filter HZ [--force-filter-damping Z] [--force-filter-order 1|2], range-checked.
std::optional<theory::ForceSensorFilter> force_filter_of(const SizeOptions& o, double rate_hz) {
    if (!o.force_filter_hz) return std::nullopt;
    const theory::ForceSensorFilter filter{*o.force_filter_hz, o.force_filter_damping,
                                           o.force_filter_order};
    try {
        theory::check_force_sensor_filter(filter, rate_hz);
    } catch (const std::invalid_argument& error) {
        throw UsageError(std::string("--force-filter / --force-filter-damping / "
                                     "--force-filter-order: ") +
                         error.what());
    }
    return filter;
}

nlohmann::ordered_json filter_fields(const std::optional<theory::ForceSensorFilter>& filter) {
    return filter ? nlohmann::ordered_json(*filter) : nlohmann::ordered_json(nullptr);
}

/// The sized design held against the exact sampled-data model, the ground truth the
/// frequency-domain models approximate. Warns on stderr when it disagrees.
nlohmann::ordered_json exact_cross_check(const DesignInput& input,
                                         const theory::SpringDamperCoupling& coupling,
                                         const tune::StabilityAssumption& assumption,
                                         bool* stable) {
    const tune::ExactCheck exact =
        tune::check_exact(input.device, coupling, input.rate_hz, assumption, input.delay_periods());
    *stable = exact.stable;
    if (!exact.stable) {
        std::cerr << "haptic-tune: the exact sampled-data model finds this design unstable: "
                  << exact.worst_operator.describe() << " against "
                  << exact.worst_environment.describe()
                  << " grows by |z| = " << exact.worst_spectral_radius << " per tick at "
                  << exact.worst_frequency_hz << " Hz, for " << assumption.describe()
                  << ". Only the passive model (the default) holds for every passive "
                     "operator (docs/stability-models.md); exit 1.\n";
    }
    return exact;
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
    nlohmann::ordered_json out = {{"display", "impedance"}};
    out.update(nlohmann::ordered_json(sizing));
    out["model"] = std::string(theory::to_string(model));
    add_input_fields(input, out);
    bool stable = true;
    if (!o.skip_exact_check)
        out["exact_check"] = exact_cross_check(input, sizing.coupling, {}, &stable);
    print_result(out, o.json);
    return stable ? kExitOk : kExitVerdictNo;
}

/// The passive model's largest k_c at the coupling's b_c: (21) by tune::size_impedance_coupling
/// against every passive environment, a bisection on tune::check_passive_scene (b >= λ is
/// monotone enough in k_c) against a scene's. A b_c that leaves no stiffness is no design.
struct PassiveLimit {
    double stiffness_n_per_m = 0.0;
    double rejected_n_per_m = 0.0;  ///< the bisection's rejected end; the sizing's own k_c
    int checks = 0;
};
PassiveLimit passive_stiffness_limit(const DesignInput& input,
                                     const theory::SpringDamperCoupling& coupling,
                                     const tune::StabilityAssumption& assumption) {
    PassiveLimit limit;
    if (assumption.environments.every_passive()) {
        tune::ImpedanceSizingRequest request;
        request.device = input.device;
        request.rate_hz = input.rate_hz;
        request.model = {theory::HoldModel::passive, input.delay_periods()};
        request.velocity_filter_hz = coupling.velocity_filter_hz;
        request.coupling_damping_n_s_per_m = coupling.damping_n_s_per_m;
        const tune::ImpedanceSizing sizing = tune::size_impedance_coupling(request);
        limit.stiffness_n_per_m = sizing.coupling.stiffness_n_per_m;
        limit.rejected_n_per_m = sizing.coupling.stiffness_n_per_m;
        limit.checks = 1;
        return limit;
    }
    const auto stable = [&](double k) {
        ++limit.checks;
        theory::SpringDamperCoupling trial = coupling;
        trial.stiffness_n_per_m = k;
        return tune::check_passive_scene(input.device, trial, input.rate_hz,
                                         assumption.environments.scene, input.delay_periods())
            .stable;
    };
    double lo = 0.0, hi = 2.0 * input.device.damping_n_s_per_m * input.rate_hz;
    if (stable(0.0)) {
        while (stable(hi) && hi < tune::kMaxCouplingStiffness) {
            lo = hi;
            hi = std::min(2.0 * hi, tune::kMaxCouplingStiffness);
        }
        while (hi - lo > 1e-4 * hi) (stable(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
    } else {
        hi = 0.0;
    }
    limit.stiffness_n_per_m = lo;
    limit.rejected_n_per_m = hi;
    return limit;
}

/// Throws InfeasibleCoupling when a limit is no design: no stiffness at all at this b_c.
void require_stiffness(double stiffness_n_per_m, double damping_n_s_per_m,
                       const tune::StabilityAssumption& assumption, const DesignInput& input) {
    if (stiffness_n_per_m > 0.0) return;
    std::ostringstream why;
    why << "coupling damping b_c = " << damping_n_s_per_m
        << " N s/m leaves no stiffness: no k_c > 0 is stable for " << assumption.describe()
        << " with the device's b = " << input.device.damping_n_s_per_m << " N s/m";
    if (input.delay_periods() > 0.0) why << " and " << input.delay_periods() << " periods of delay";
    why << " (docs/stability-models.md); lower --coupling-damping";
    throw tune::InfeasibleCoupling(why.str());
}

/// How far past the proven limit the exact model looks for the operator that reaches it.
constexpr double kWitnessFactor = 1.03;

/// The exact model's job where the limit is proven: name an operator (and environment) that
/// is unstable just past it, kWitnessFactor times the limit. A search that finds none says so:
/// the proof may be conservative there, or the search does not reach its operators yet.
nlohmann::ordered_json witness_past(const DesignInput& input,
                                    const theory::SpringDamperCoupling& at_limit,
                                    const tune::StabilityAssumption& assumption) {
    theory::SpringDamperCoupling past = at_limit;
    past.stiffness_n_per_m *= kWitnessFactor;
    const tune::ExactCheck search =
        tune::check_exact(input.device, past, input.rate_hz, assumption, input.delay_periods(),
                          tune::SearchFor::witness);
    nlohmann::ordered_json out = {{"stiffness", past.stiffness_n_per_m},
                                  {"factor", kWitnessFactor},
                                  {"found", !search.stable}};
    if (search.stable) {
        out["note"] =
            "the exact model's search finds no unstable operator here: the proof may be "
            "conservative at this design, or the operators that reach it are beyond the "
            "search (docs/stability-models.md)";
    }
    out["search"] = search;
    return out;
}

/// The largest k_c at b_c for a stated assumption (an operator class, a scene), or by the
/// exact model. The passive model's proven limit; for a class, the class's port condition's
/// (tune/class_proof.hpp), never below the passive one (the class is a subset of every
/// passive operator). With --model exact, the operator the exact model finds unstable just
/// past the answer.
int run_assumed(const SizeOptions& o, const DesignInput& input,
                const tune::StabilityAssumption& assumption) {
    if (o.optimize_damping) {
        throw UsageError(
            "--optimize-damping sizes under the passive model against every "
            "passive environment; with --model exact, --operator-class or --scene, "
            "give --coupling-damping and compare values (docs/stability-models.md "
            "charts the limit against b_c)");
    }
    const double damping =
        o.coupling_damping.value_or(input.coupling_damping_n_s_per_m.value_or(0.0));
    tune::check_coupling_gains({0.0, damping});
    nlohmann::ordered_json out = {{"display", "impedance"}};
    theory::SpringDamperCoupling coupling{0.0, damping};
    coupling.velocity_filter_hz = input.velocity_filter_hz;
    const bool exact = o.model == "exact";
    PassiveLimit passive;
    try {
        passive = passive_stiffness_limit(input, coupling, assumption);
    } catch (const tune::InfeasibleCoupling&) {
        if (!assumption.operators) throw;  // a class may still hold where the passive bound cannot
    }
    double rejected = passive.rejected_n_per_m;
    int checks = passive.checks;
    coupling.stiffness_n_per_m = passive.stiffness_n_per_m;
    std::string proof(tune::kPassivePortCondition);
    if (assumption.operators) {
        const tune::ClassProver prover(input.device, *assumption.operators, input.rate_hz,
                                       input.delay_periods());
        const tune::ClassProver::Limit limit =
            prover.stiffness_limit(coupling, passive.stiffness_n_per_m);
        checks += limit.proofs;
        if (limit.stiffness_n_per_m > passive.stiffness_n_per_m) {
            coupling.stiffness_n_per_m = limit.stiffness_n_per_m;
            rejected = limit.rejected_n_per_m;
            proof = tune::kClassPortCondition;
        }
    }
    require_stiffness(coupling.stiffness_n_per_m, damping, assumption, input);
    out["stiffness"] = coupling.stiffness_n_per_m;
    out["damping"] = damping;
    out["rejected_stiffness"] = rejected;
    out["model"] = o.model;
    out["holds_for"] = assumption.describe();
    out["proof"] = proof;
    out["checks"] = checks;
    add_input_fields(input, out);
    bool stable = true;
    if (!o.skip_exact_check) {
        out["exact_check"] = exact_cross_check(input, coupling, assumption, &stable);
        if (exact) out["witness"] = witness_past(input, coupling, assumption);
    }
    print_result(out, o.json);
    return stable ? kExitOk : kExitVerdictNo;
}

/// The admittance display's PI gains (pi_gains {kp, ki}) and the input it was sized for.
void add_pi_and_input_fields(const theory::PiVelocityLoop& loop, const DesignInput& input,
                             nlohmann::ordered_json& out) {
    out["pi_gains"] = {{"kp", loop.proportional_gain_n_s_per_m},
                       {"ki", loop.integral_gain_n_per_m}};
    add_input_fields(input, out);
}

void warn_exact_admittance_rejects(const tune::AdmittanceExactCheck& exact) {
    std::cerr << "haptic-tune: the exact admittance model finds this design unstable: "
              << exact.worst_operator.describe() << " against "
              << exact.worst_environment.describe()
              << " grows by |z| = " << exact.worst_spectral_radius << " per tick at "
              << exact.worst_frequency_hz
              << " Hz. (37) leaves out the aliasing of the hold and of the force sensor "
                 "(docs/stability-models.md); exit 1.\n";
}

int run_admittance(const SizeOptions& o, const DesignInput& input, const std::string& model) {
    const theory::PiVelocityLoop loop = o.display.pi_loop();
    if (loop.proportional_gain_n_s_per_m == 0.0 && loop.integral_gain_n_per_m == 0.0) {
        throw UsageError(
            "--kp 0 with --ki 0: the admittance display's velocity loop (27) has no gain, so "
            "the device renders nothing and there is no coupling to size; give --kp > 0 "
            "(N s/m) or --ki > 0 (N/m)");
    }
    const double damping = o.coupling_damping.value_or(std::numeric_limits<double>::infinity());
    const std::optional<theory::ForceSensorFilter> filter = force_filter_of(o, input.rate_hz);
    if (filter && model != "passive" && model != "exact") {
        throw UsageError("--force-filter is for --model passive or exact; (37) has no filter");
    }
    if (model == "passive") {
        if (o.optimize_damping) {
            throw UsageError(
                "--model passive sizes m_c for a given --coupling-damping (default none): "
                "--optimize-damping is for (37)");
        }
        // Without a filter (or with a first-order one) this throws with the explanation.
        tune::PassiveAdmittanceSizingRequest request{input.device,          loop,    input.rate_hz,
                                                     input.delay_periods(), damping, filter};
        const tune::PassiveAdmittanceSizing sizing =
            tune::size_admittance_coupling_passive(request);
        nlohmann::ordered_json out = {{"display", "admittance"}};
        out.update(nlohmann::ordered_json(sizing));
        out["model"] = "passive";
        out["force_filter"] = filter_fields(filter);
        out["holds_for"] =
            "every passive operator and every passive environment, with the force sensor "
            "behind the " +
            filter->describe() +
            " ((P2) with the whole alias sums, tails bounded; frequencies on a grid of "
            "4096 + 256 log-spaced points, refined at the worst)";
        add_pi_and_input_fields(loop, input, out);
        if (!sizing.exact.stable) warn_exact_admittance_rejects(sizing.exact);
        print_result(out, o.json);
        return sizing.exact.stable ? kExitOk : kExitVerdictNo;
    }
    if (model == "exact") {
        if (o.optimize_damping) {
            throw UsageError(
                "--model exact sizes m_c for a given --coupling-damping (default none): "
                "--optimize-damping is for (37)");
        }
        tune::ExactAdmittanceSizingRequest request;
        request.device = input.device;
        request.loop = loop;
        request.rate_hz = input.rate_hz;
        request.delay_periods = input.delay_periods();
        request.coupling_damping_n_s_per_m = damping;
        request.force_filter = filter;
        const tune::ExactAdmittanceSizing sizing = tune::size_admittance_coupling_exact(request);
        nlohmann::ordered_json out = {{"display", "admittance"}};
        out.update(nlohmann::ordered_json(sizing));
        out["model"] = "exact";
        out["force_filter"] = filter_fields(filter);
        out["safety_factor"] = request.safety_factor;
        out["holds_for"] =
            "the operators and environments the exact admittance model checks (its sweep: "
            "hands-off, heavy hands, stiff grasps, two-mass grasps, steel grips resonating "
            "with the handle at up to the Nyquist frequency; free space, rigid wall, virtual "
            "masses and mass-springs), not every passive operator";
        add_pi_and_input_fields(loop, input, out);
        if (!sizing.check.stable) warn_exact_admittance_rejects(sizing.check);
        print_result(out, o.json);
        return sizing.check.stable ? kExitOk : kExitVerdictNo;
    }
    if (input.delay_s != 0.0) {
        throw UsageError(
            "(37) has no loop delay: --display admittance --model " + model +
            " needs --delay 0 (over a config's [device.model] delay); --model exact takes it");
    }
    const theory::HoldModel hold = *theory::parse_hold_model(model);
    tune::AdmittanceSizingRequest request;
    request.device = input.device;
    request.loop = loop;
    request.rate_hz = input.rate_hz;
    request.model = hold;
    if (!o.optimize_damping) request.coupling_damping_n_s_per_m = damping;
    const tune::AdmittanceSizing sizing = tune::size_admittance_coupling(request);
    nlohmann::ordered_json out = {{"display", "admittance"}};
    out.update(nlohmann::ordered_json(sizing));
    out["model"] = model;
    add_pi_and_input_fields(loop, input, out);
    bool stable = true;
    if (!o.skip_exact_check) {
        const tune::AdmittanceExactCheck exact =
            tune::check_exact_admittance({input.device, loop, sizing.coupling, input.rate_hz, 0.0});
        stable = exact.stable;
        out["exact_check"] = exact;
        if (!stable) warn_exact_admittance_rejects(exact);
    }
    print_result(out, o.json);
    return stable ? kExitOk : kExitVerdictNo;
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
    add_model_option(*command, options->model, {"passive", "exact", "paper", "encoder"});
    add_assumption_options(*command, options->assumption);
    add_display_options(*command, options->display);
    command
        ->add_option("--force-filter", options->force_filter_hz,
                     "admittance display: cutoff f_aa (Hz) of the analog low-pass on the force "
                     "sensor, 0 < f_aa <= 100 x rate (default none)")
        ->check(non_negative_finite("Hz"));
    command->add_option("--force-filter-damping", options->force_filter_damping,
                        "damping ratio of the second-order force filter, (0, 10] (default "
                        "0.7071, Butterworth)");
    command->add_option("--force-filter-order", options->force_filter_order,
                        "order of the force filter, 1 or 2 (default 2; 1 sizes nothing)");
    command->add_flag("--json", options->json, "print the result as JSON");
    command->add_flag("--no-exact-check", options->skip_exact_check,
                      "skip holding a (21) or (37) answer against the exact model");
    command->callback([options, &invocation] {
        invocation.run = [options] {
            const DesignInput input = resolve_design_input(options->device);
            const tune::StabilityAssumption assumption =
                resolve_assumption(options->assumption, options->model);
            const bool declared = assumption.operators || !assumption.environments.every_passive();
            if (options->display.admittance()) {
                if (input.velocity_filter_hz != 0.0) {
                    throw UsageError(
                        "--velocity-filter is the impedance display's coupling damper; the "
                        "admittance display's coupling (32) has none");
                }
                if (declared) {
                    throw UsageError(
                        "--operator-class and --scene size the impedance display "
                        "only");
                }
                return run_admittance(*options, input, options->model);
            }
            if (options->force_filter_hz) {
                throw UsageError("--force-filter is the admittance display's force sensor");
            }
            if (declared || options->model == "exact") {
                return run_assumed(*options, input, assumption);
            }
            return run_impedance(*options, input, *theory::parse_hold_model(options->model));
        };
    });
}

}  // namespace hapticd::tools
