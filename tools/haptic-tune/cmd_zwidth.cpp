// haptic-tune zwidth: the range of impedances the interface can present to the operator,
// |Z_min| and |Z_max| against frequency, per stability model.
//   impedance display, (24)-(25):  Z_min = Z_d,  Z_max = Z_d + Z_c H   (so (26) holds),
//                                  with the loop delay in H (--delay, [device.model] delay);
//   admittance display, (42)-(43): Z_min = Z_cA / (T + Z_cA/Z_dA),  Z_max = Z_dA.
// Z_d and H are the model's device impedance and hold term (theory/benchmark.hpp).
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "chart_design.hpp"
#include "chart_script.hpp"
#include "commands.hpp"
#include "hapticd/theory/unit_circle.hpp"
#include "hapticd/theory/zwidth.hpp"
#include "hapticd/tune/coupling_sizing.hpp"
#include "hapticd/tune/input_checks.hpp"
#include "hapticd/tune/result_json.hpp"

namespace hapticd::tools {
namespace {

struct ZwidthOptions {
    ChartOptions chart;
    DisplayOptions display;
    std::optional<double> coupling_mass;
};

/// One model's |Z_min| and |Z_max| on the frequency axis.
template <typename ZminFn, typename ZmaxFn>
nlohmann::ordered_json magnitudes(const std::vector<double>& frequencies, double period,
                                  ZminFn zmin, ZmaxFn zmax) {
    std::vector<double> min_magnitude;
    std::vector<double> max_magnitude;
    min_magnitude.reserve(frequencies.size());
    max_magnitude.reserve(frequencies.size());
    for (const double f : frequencies) {
        const double theta = theory::normalized_frequency(f, period);
        min_magnitude.push_back(std::abs(zmin(theta)));
        max_magnitude.push_back(std::abs(zmax(theta)));
    }
    return {{"zmin_magnitude", min_magnitude}, {"zmax_magnitude", max_magnitude}};
}

/// The chart of one display: its design and its curves, after the input they are for
/// (add_input_fields).
nlohmann::ordered_json chart_json(const DesignInput& input, const char* display,
                                  const std::string& title, nlohmann::ordered_json design,
                                  const std::vector<double>& frequencies,
                                  nlohmann::ordered_json per_model) {
    nlohmann::ordered_json chart = {{"kind", "zwidth"}, {"display", display}, {"title", title}};
    std::string names;  // the models, in the order drawn
    for (const auto& [name, curves] : per_model.items()) {
        names += (names.empty() ? "" : ", ") + name;
    }
    chart["caption"] =
        chart_caption(std::string("haptic-tune zwidth, the ") + display + " display", names, input);
    add_input_fields(input, chart);
    chart["nyquist_hz"] = theory::nyquist_hz(1.0 / input.rate_hz);
    chart["design"] = std::move(design);
    chart["units"] = "N s/m";
    chart["frequency_hz"] = frequencies;
    chart["models"] = std::move(per_model);
    return chart;
}

int finish(const ZwidthOptions& o, nlohmann::ordered_json chart) {
    if (!o.chart.look.out.empty()) render_chart(chart, o.chart.look);
    if (o.chart.look.json) {
        print_result(chart, true);
        return kExitOk;
    }
    nlohmann::ordered_json summary = {{"chart", o.chart.look.out},   {"display", chart["display"]},
                                      {"design", chart["design"]},   {"device", chart["device"]},
                                      {"rate_hz", chart["rate_hz"]}, {"delay_s", chart["delay_s"]}};
    // The Z-width as one number per model: |Z_max|/|Z_min| at the lowest charted frequency.
    const std::vector<double> f = chart["frequency_hz"];
    for (const auto& [name, curves] : chart["models"].items()) {
        const std::vector<double> zmin = curves["zmin_magnitude"];
        const std::vector<double> zmax = curves["zmax_magnitude"];
        summary["zmax/zmin at " + number_text(f.front(), 4) + " Hz [" + name + "]"] =
            zmax.front() / zmin.front();
    }
    print_result(summary, false);
    return kExitOk;
}

int run_impedance(const ZwidthOptions& o, const std::vector<theory::HoldModel>& models,
                  const DesignInput& input) {
    if (o.display.kp || o.display.ki || o.coupling_mass) {
        throw UsageError("--kp, --ki and --coupling-mass are for --display admittance");
    }
    const ImpedanceDesign design = resolve_impedance_design(o.chart, input);
    const double period = 1.0 / input.rate_hz;
    const std::vector<double> frequencies = chart_frequencies_hz(input.rate_hz, o.chart.points);
    nlohmann::ordered_json per_model = nlohmann::ordered_json::object();
    for (const theory::HoldModel hold : models) {
        const theory::LoopModel model{hold, input.delay_periods()};
        per_model[std::string(theory::to_string(hold))] = magnitudes(
            frequencies, period,
            [&](double theta) {
                return theory::impedance_display_zmin(input.device, model, theta, period);
            },
            [&](double theta) {
                return theory::impedance_display_zmax(input.device, design.coupling, model, theta,
                                                      period);
            });
    }
    return finish(o, chart_json(input, "impedance",
                                "Z-width of the impedance display, (24)-(25): " +
                                    describe_device(input) + "\n" + describe_design(design),
                                design_json(design), frequencies, per_model));
}

int run_admittance(const ZwidthOptions& o, const std::vector<theory::HoldModel>& models,
                   const DesignInput& input) {
    const theory::PiVelocityLoop loop = o.display.pi_loop();
    if (input.delay_s > 0.0) {
        throw UsageError("--delay " + number_text(input.delay_s) +
                         " s: the admittance display's models (27)-(43) have no loop delay; "
                         "chart it with --delay 0 (or a config whose [device.model] delay is 0)");
    }
    if (o.chart.stiffness) {
        throw UsageError(
            "--stiffness is the impedance display's coupling; the admittance "
            "display's coupling is --coupling-mass and --coupling-damping");
    }
    tune::check_device(input.device);
    tune::check_rate(input.rate_hz);
    theory::MassDamperCoupling coupling;
    coupling.damping_n_s_per_m =
        o.chart.coupling_damping.value_or(std::numeric_limits<double>::infinity());
    tune::check_positive_or_infinite("coupling damping b_c", coupling.damping_n_s_per_m, "N s/m");
    std::string source = "flags";
    double sized_binding_hz = 0.0;
    if (o.coupling_mass) {
        coupling.mass_kg = *o.coupling_mass;
    } else {
        tune::AdmittanceSizingRequest request;
        request.device = input.device;
        request.loop = loop;
        request.rate_hz = input.rate_hz;
        request.model = theory::HoldModel::encoder;
        request.coupling_damping_n_s_per_m = coupling.damping_n_s_per_m;
        const tune::AdmittanceSizing sizing = tune::size_admittance_coupling(request);
        coupling = sizing.coupling;
        source = "sized";
        sized_binding_hz = sizing.binding_frequency_hz;
    }
    const double period = 1.0 / input.rate_hz;
    const std::vector<double> frequencies = chart_frequencies_hz(input.rate_hz, o.chart.points);
    nlohmann::ordered_json per_model = nlohmann::ordered_json::object();
    for (const theory::HoldModel model : models) {
        per_model[std::string(theory::to_string(model))] = magnitudes(
            frequencies, period,
            [&](double theta) {
                return theory::admittance_display_zmin(input.device, loop, coupling, model, theta,
                                                       period);
            },
            [&](double theta) {
                return theory::admittance_display_zmax(input.device, loop, model, theta, period);
            });
    }
    const bool pure_mass = std::isinf(coupling.damping_n_s_per_m);
    nlohmann::ordered_json design = {
        {"coupling_mass", coupling.mass_kg},
        // null: no series damper (b_c = inf), the coupling is a pure mass.
        {"damping", pure_mass ? nlohmann::ordered_json(nullptr)
                              : nlohmann::ordered_json(coupling.damping_n_s_per_m)},
        {"pi_gains",
         {{"kp", loop.proportional_gain_n_s_per_m}, {"ki", loop.integral_gain_n_per_m}}},
        {"source", source},
    };
    if (source == "sized") {
        design["sizing_model"] = "encoder";
        design["sizing_binding_frequency_hz"] = sized_binding_hz;
    }
    std::string described =
        "k_p = " + number_text(loop.proportional_gain_n_s_per_m, 4) +
        " N s/m, k_i = " + number_text(loop.integral_gain_n_per_m, 4) +
        " N/m; m_c = " + number_text(coupling.mass_kg, 4) + " kg, b_c = " +
        (pure_mass ? std::string("none") : number_text(coupling.damping_n_s_per_m, 4) + " N s/m");
    if (source == "sized") described += " (sized from (37) with the encoder model)";
    return finish(o, chart_json(input, "admittance",
                                "Z-width of the admittance display, (42)-(43): " +
                                    describe_device(input) + "\n" + described,
                                design, frequencies, per_model));
}

int run_zwidth(const ZwidthOptions& o) {
    const std::vector<theory::HoldModel> models = parse_model_list(o.chart.models);
    check_chart_output(o.chart.look);
    const DesignInput input = resolve_design_input(o.chart.device);
    if (o.display.admittance()) return run_admittance(o, models, input);
    return run_impedance(o, models, input);
}

}  // namespace

void add_zwidth_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<ZwidthOptions>();
    CLI::App* command = app.add_subcommand(
        "zwidth",
        "Chart the Z-width: |Z_min| and |Z_max| the interface can present against frequency, "
        "(24)-(25) for the impedance display, (42)-(43) for the admittance display");
    add_chart_options(*command, options->chart);
    command->get_option("--coupling-damping")
        ->description(
            "coupling damping b_c (N s/m); impedance display: default [coupling] "
            "damping from --config, else 0; admittance display: the series damper "
            "of (32), default none (a pure mass)");
    add_display_options(*command, options->display);
    add_delay_option(*command, options->chart.device);
    add_velocity_filter_option(*command, options->chart.device);
    command
        ->add_option("--coupling-mass", options->coupling_mass,
                     "admittance display: coupling mass m_c (kg); default sized from (37) "
                     "with the encoder model")
        ->check(positive_finite("kg"));
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_zwidth(*options); }; });
}

}  // namespace hapticd::tools
