// haptic-tune identify: the device's mass, damping, Coulomb friction and force offset from a
// recorded run (hapticd --identify, or any telemetry CSV with t_s, x{i}_m and f{i}_n), with
// their standard errors (hapticd/tune/identification.hpp, docs/identification.md).
// Exit 0 identified, 2 on bad input or a log that cannot identify the model.
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>

#include "chart_options.hpp"
#include "chart_script.hpp"
#include "commands.hpp"
#include "hapticd/install/version.hpp"
#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/result_json.hpp"
#include "identify_chart.hpp"

namespace hapticd::tools {
namespace {

struct IdentifyOptions {
    std::string log_path;
    std::optional<int> axis;
    std::optional<double> resolution_m;
    std::optional<double> force_limit_n;
    double delay_s = 0.0;
    double segment_s = tune::IdentificationOptions{}.segment_s;
    double max_relative_std_error = tune::IdentificationOptions{}.max_relative_std_error;
    double max_stuck_fraction = tune::IdentificationOptions{}.max_stuck_fraction;
    bool json = false;
    ChartLook chart;  ///< --chart: the fit chart (identify_chart.hpp)
};

/// Draws the fit chart of `axes` and adds each axis' free-run numbers to its result.
void draw_fit_chart(const IdentifyOptions& o, const tune::TelemetryLog& log,
                    const std::vector<tune::IdentifiedAxis>& axes,
                    std::vector<nlohmann::ordered_json>& results) {
    std::vector<FreeRunFit> fits;
    nlohmann::ordered_json chart = identify_fit_chart(log, axes, fits);
    chart["title"] =
        "haptic-tune identify: measured velocity against the identified model "
        "run free under the logged force";
    chart["caption"] = "model (10) with Coulomb friction and offset, exact zero-order hold; " +
                       o.log_path + "; hapticd " + install::kVersion;
    render_chart(chart, o.chart);
    for (std::size_t i = 0; i < results.size(); ++i) {
        results[i]["chart"] = o.chart.out;
        results[i]["free_run_velocity_rms_error_mps"] = fits[i].velocity_rms_error_mps;
        results[i]["free_run_explained_fraction"] = fits[i].explained_fraction;
    }
}

int run_identify(const IdentifyOptions& o) {
    if (!o.chart.out.empty()) check_chart_output(o.chart);
    tune::TelemetryLog log;
    try {
        log = tune::read_telemetry_log(o.log_path, tune::TelemetryLogOptions::identification());
    } catch (const tune::LogFormatError& e) {
        std::cerr << "haptic-tune: bad log: " << e.what() << '\n';
        return kExitBadInput;
    }
    tune::IdentificationOptions options;
    options.segment_s = o.segment_s;
    options.resolution_m = o.resolution_m;
    options.force_limit_n = o.force_limit_n;
    options.delay_s = o.delay_s;
    options.max_relative_std_error = o.max_relative_std_error;
    options.max_stuck_fraction = o.max_stuck_fraction;
    std::vector<tune::IdentifiedAxis> axes;
    try {
        if (o.axis) {
            axes.push_back(tune::identify_axis(log, *o.axis, options));
        } else {
            axes = tune::identify_all_axes(log, options);
        }
    } catch (const tune::IdentificationRefused& e) {
        std::cerr << "haptic-tune: " << o.log_path << ": " << e.what() << " ["
                  << tune::to_string(e.reason()) << "]\n";
        return kExitBadInput;
    }
    for (const tune::IdentifiedAxis& a : axes) {
        if (!a.report.converged) {
            std::cerr << "haptic-tune: warning: axis " << a.axis
                      << ": the fit stopped before Ceres' tolerances were met ("
                      << a.report.termination << "); check the residual\n";
        }
    }
    std::vector<nlohmann::ordered_json> results(axes.begin(), axes.end());
    if (!o.chart.out.empty()) draw_fit_chart(o, log, axes, results);
    if (results.size() == 1) {
        results.front()["log"] = o.log_path;
        print_result(results.front(), o.json);
        return kExitOk;
    }
    if (o.json) {
        print_result({{"log", o.log_path}, {"axes", results}}, true);
        return kExitOk;
    }
    for (std::size_t i = 0; i < results.size(); ++i) {
        if (i > 0) std::cout << '\n';
        print_result(results[i], false);
    }
    return kExitOk;
}

}  // namespace

void add_identify_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<IdentifyOptions>();
    CLI::App* command = app.add_subcommand(
        "identify",
        "Identify the device's mass m, damping b, Coulomb friction F_c and force offset F_0 "
        "from a recorded run (telemetry CSV: t_s, x{i}_m, f{i}_n), with standard errors; "
        "exit 2 if the log cannot identify them (the message says why)");
    command->add_option("LOG", options->log_path, "telemetry CSV of the excitation run")
        ->required();
    command->add_option("--axis", options->axis, "identify only this axis (default: every axis)")
        ->check(CLI::Range(0, 63));
    command
        ->add_option("--resolution", options->resolution_m,
                     "encoder resolution, m per count (default: the smallest step between "
                     "logged positions)")
        ->check(positive_finite("m"));
    command
        ->add_option("--force-limit", options->force_limit_n,
                     "the device's force limit, N: refuse the log if the force sits there")
        ->check(positive_finite("N"));
    command
        ->add_option("--delay", options->delay_s,
                     "the loop delay, s, from a position's sample to the force computed from it "
                     "acting (haptic-tune diag measures it: its loop_delay p50); the fit shifts "
                     "the logged forces by it (default 0; under 10 periods)")
        ->check(non_negative_finite("s"));
    command
        ->add_option("--segment", options->segment_s,
                     "length of a shooting segment, s (default 0.02; docs/identification.md)")
        ->check(CLI::Range(0.001, 1000.0));
    command
        ->add_option("--max-relative-std-error", options->max_relative_std_error,
                     "refuse the log if m or b has a larger relative standard error "
                     "(default 0.01)")
        ->check(positive_finite("(fraction)"));
    command
        ->add_option("--max-stuck-fraction", options->max_stuck_fraction,
                     "refuse the log if the fitted handle sits in stiction after more than "
                     "this fraction of the periods (default 0.25)")
        ->check(CLI::Range(0.0, 1.0));
    command->add_flag("--json", options->json, "print the result as JSON");
    add_chart_file_options(*command, options->chart, "--chart",
                           "draw the fit: the measured velocity against the identified model run "
                           "free under the logged force (.png, .svg or .pdf)");
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_identify(*options); }; });
}

}  // namespace hapticd::tools
