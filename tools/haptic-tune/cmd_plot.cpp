// haptic-tune plot: the paper's design procedure as a chart. "Plot the right-hand side of
// (21) versus frequency, then synthesize 1/Z_c so that its real part is positive and
// exceeds this lower bound": one bound curve per stability model, the coupling's
// conductance Re(1/Z_c) of (16), and each model's binding (worst) frequency.
#include <algorithm>
#include <memory>

#include "chart_design.hpp"
#include "chart_script.hpp"
#include "commands.hpp"
#include "hapticd/theory/coupling_check.hpp"
#include "hapticd/theory/unit_circle.hpp"
#include "hapticd/tune/result_json.hpp"

namespace hapticd::tools {
namespace {

nlohmann::ordered_json model_curve(const DesignInput& input, const ImpedanceDesign& design,
                                   theory::HoldModel hold, const std::vector<double>& frequencies) {
    const theory::LoopModel model{hold, input.delay_periods()};
    const double period = 1.0 / input.rate_hz;
    const double b = input.device.damping_n_s_per_m;
    std::vector<double> bound;
    std::vector<double> margin;  // +inf (JSON null) where the bound is zero
    bound.reserve(frequencies.size());
    margin.reserve(frequencies.size());
    for (const double f : frequencies) {
        const double theta = theory::normalized_frequency(f, period);
        bound.push_back(theory::conductance_bound(model, b, theta));
        margin.push_back(
            theory::coupling_margin(input.device, design.coupling, model, theta, period));
    }
    const theory::CouplingCheck check =
        theory::check_coupling(input.device, design.coupling, model, input.rate_hz);
    // Where to mark the binding point: the worst frequency, or the chart's left edge when
    // (21) binds below it (worst_frequency_hz = 0 is the limit f -> 0).
    const double marker_hz = std::max(check.worst_frequency_hz, frequencies.front());
    const double marker_theta = theory::normalized_frequency(marker_hz, period);
    nlohmann::ordered_json curve = {{"bound", bound}, {"margin", margin}};
    curve.update(nlohmann::ordered_json(check));
    curve["marker"] = {
        {"frequency_hz", marker_hz},
        {"bound", theory::conductance_bound(model, b, marker_theta)},
        {"conductance", theory::coupling_conductance(design.coupling, marker_theta, period)}};
    return curve;
}

int run_plot(const ChartOptions& o) {
    const std::vector<theory::HoldModel> models = parse_model_list(o.models);
    check_chart_output(o.look);
    const DesignInput input = resolve_design_input(o.device);
    const ImpedanceDesign design = resolve_impedance_design(o, input);
    const double period = 1.0 / input.rate_hz;

    const std::vector<double> frequencies = chart_frequencies_hz(input.rate_hz, o.points);
    std::vector<double> conductance;
    conductance.reserve(frequencies.size());
    for (const double f : frequencies) {
        conductance.push_back(theory::coupling_conductance(
            design.coupling, theory::normalized_frequency(f, period), period));
    }
    nlohmann::ordered_json per_model = nlohmann::ordered_json::object();
    for (const theory::HoldModel model : models) {
        per_model[std::string(theory::to_string(model))] =
            model_curve(input, design, model, frequencies);
    }
    const std::string delay =
        input.delay_s > 0.0 ? ", loop delay " + number_text(input.delay_s * 1e3, 4) + " ms" : "";
    const std::string title = "Design procedure, (21): " + describe_device(input) + delay + "\n" +
                              describe_design(design);
    nlohmann::ordered_json chart = {{"kind", "design-procedure"}, {"title", title}};
    add_input_fields(input, chart);
    chart["nyquist_hz"] = theory::nyquist_hz(period);
    chart["design"] = design_json(design);
    chart["frequency_hz"] = frequencies;
    chart["coupling_conductance"] = conductance;
    chart["models"] = per_model;
    chart["caption"] =
        chart_caption("haptic-tune plot, the design procedure of (21)", model_names(models), input);
    if (!o.look.out.empty()) render_chart(chart, o.look);

    if (o.look.json) {
        print_result(chart, true);
        return kExitOk;
    }
    nlohmann::ordered_json summary = {
        {"chart", o.look.out},
        {"stiffness", design.coupling.stiffness_n_per_m},
        {"damping", design.coupling.damping_n_s_per_m},
        {"coupling_source", design.source == "sized"
                                ? "sized from (21) with the passive model (no --stiffness, "
                                  "no [coupling] stiffness)"
                                : design.source},
    };
    add_input_fields(input, summary);
    for (const auto& [name, curve] : per_model.items()) {
        summary["worst_margin[" + name + "]"] = curve["worst_margin"];
        summary["worst_frequency_hz[" + name + "]"] = curve["worst_frequency_hz"];
        summary["unconditionally_stable[" + name + "]"] = curve["unconditionally_stable"];
    }
    print_result(summary, false);
    return kExitOk;
}

}  // namespace

void add_plot_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<ChartOptions>();
    CLI::App* command = app.add_subcommand(
        "plot",
        "Chart the design procedure of (21): the least coupling conductance each stability "
        "model needs against frequency, and the coupling's Re(1/Z_c)");
    add_chart_options(*command, *options);
    add_delay_option(*command, options->device);
    add_velocity_filter_option(*command, options->device);
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_plot(*options); }; });
}

}  // namespace hapticd::tools
