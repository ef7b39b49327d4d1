// haptic-tune identify: the device's mass, damping, Coulomb friction and force offset from a
// recorded run (hapticd --identify, or any telemetry CSV with t_s, x{i}_m and f{i}_n), with
// their standard errors (hapticd/tune/identification.hpp, docs/identification.md).
// Exit 0 identified, 2 on bad input or a log that cannot identify the model.
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>

#include "commands.hpp"
#include "hapticd/tune/identification.hpp"
#include "hapticd/tune/result_json.hpp"

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
};

int run_identify(const IdentifyOptions& o) {
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
    if (axes.size() == 1) {
        nlohmann::ordered_json out = nlohmann::ordered_json(axes.front());
        out["log"] = o.log_path;
        print_result(out, o.json);
        return kExitOk;
    }
    if (o.json) {
        nlohmann::ordered_json list = nlohmann::ordered_json::array();
        for (const tune::IdentifiedAxis& a : axes) list.push_back(a);
        print_result({{"log", o.log_path}, {"axes", list}}, true);
        return kExitOk;
    }
    for (std::size_t i = 0; i < axes.size(); ++i) {
        if (i > 0) std::cout << '\n';
        print_result(axes[i], false);
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
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_identify(*options); }; });
}

}  // namespace hapticd::tools
