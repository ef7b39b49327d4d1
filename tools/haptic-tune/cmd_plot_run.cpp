// haptic-tune plot-run: a recorded run (hapticd --log, hapticctl record) as a chart and a
// judgement. The chart: the handle's position x_d and the tool's x_e, the force, the energy
// stored in the coupling's spring ½ k_c Σ (x_d − x_e)² and the passivity observer's energy
// (Hannaford & Ryu), with faults and the ticks the safety layer acted on marked. The
// judgement: the oscillation of the handle about its operating point, fitted in windows
// (tune/oscillation.hpp): does it grow or die out, and how fast. Exit 0 judged, 2 for a log
// that cannot be read.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <string_view>

#include "chart_options.hpp"
#include "chart_script.hpp"
#include "chart_series.hpp"
#include "commands.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/install/version.hpp"
#include "hapticd/servo/faults.hpp"
#include "hapticd/servo/telemetry.hpp"
#include "hapticd/tune/oscillation.hpp"
#include "hapticd/tune/telemetry_log.hpp"

namespace hapticd::tools {
namespace {

struct PlotRunOptions {
    std::string log_path;
    ChartLook look;
    int axis = 0;
    std::optional<double> stiffness_n_per_m;
    std::string config_path;
    double judge_from_s = 0.2;
    double window_s = 0.1;
    std::optional<double> floor_m;  ///< default: kFloorCounts of the log's encoder count
    double growth_threshold_per_s = 0.5;
};

/// The ticks the safety layer acted on, by what it did (the `flags` column's TickFlag).
constexpr std::pair<servo::TickFlag, const char*> kMarkedFlags[] = {
    {servo::kFlagSaturated, "saturated"},
    {servo::kFlagOverspeed, "overspeed"},
    {servo::kFlagPassivityControl, "passivity_control"},
    {servo::kFlagOverrun, "overrun"},
    {servo::kFlagNoSample, "no_sample"},
};
/// Times of marked ticks kept per flag for the chart (the counts are whole).
constexpr std::size_t kMaxMarks = 2000;
/// The amplitude floor by default: dither up to this many encoder counts is quantisation.
constexpr double kFloorCounts = 3.0;
/// The floor when the log shows no encoder count (its positions never step).
constexpr double kFallbackFloorM = 1e-6;

/// The encoder count the log shows: its smallest nonzero step between positions (as
/// haptic-tune identify estimates the resolution); 0 when the position never moves.
double smallest_step_m(const std::vector<double>& x) {
    double step = 0.0;
    for (std::size_t i = 1; i < x.size(); ++i) {
        const double d = std::abs(x[i] - x[i - 1]);
        if (d > 0.0 && (step == 0.0 || d < step)) step = d;
    }
    return step;
}

const std::vector<double>& required_column(const tune::TelemetryLog& log, const std::string& name) {
    const std::vector<double>* column = log.column(name);
    if (column == nullptr) {
        throw UsageError(log.source + ": no column " + name +
                         " (the log's columns: see its header)");
    }
    return *column;
}

/// The sampling period: the median step of t_s.
double median_period_s(const std::vector<double>& t) {
    std::vector<double> steps;
    steps.reserve(t.size());
    for (std::size_t i = 1; i < t.size(); ++i) steps.push_back(t[i] - t[i - 1]);
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2),
                     steps.end());
    return steps[steps.size() / 2];
}

/// k_c from the row `from_row` on: one entry at row 0, and one at each coupling change the
/// log's marks name.
struct StiffnessChange {
    std::size_t from_row = 0;
    double stiffness_n_per_m = 0.0;
};

/// Where k_c comes from: --stiffness, else --config's [coupling] stiffness, else the log's
/// own preamble (coupling_stiffness_n_per_m) and its "# mark N: coupling k_c X N/m" lines
/// (a hapticctl coupling during the run). Empty when none says.
std::vector<StiffnessChange> coupling_stiffness(const PlotRunOptions& o,
                                                const tune::TelemetryLog& log,
                                                std::string& source) {
    if (o.stiffness_n_per_m) {
        source = "--stiffness";
        return {{0, *o.stiffness_n_per_m}};
    }
    if (!o.config_path.empty()) {
        const double stiffness = daemon::load_config(o.config_path).coupling.stiffness_n_per_m;
        source = "--config";
        if (stiffness > 0.0) return {{0, stiffness}};
        return {};
    }
    const std::string* preamble = log.preamble_value("coupling_stiffness_n_per_m");
    double initial = 0.0;
    if (preamble == nullptr || !tune::parse_log_number(*preamble, initial) || !(initial > 0.0)) {
        return {};
    }
    source = "the log's preamble";
    std::vector<StiffnessChange> changes = {{0, initial}};
    constexpr std::string_view kCouplingNote = "coupling k_c ";
    for (const tune::TelemetryMark& mark : log.marks) {
        if (!mark.text.starts_with(kCouplingNote)) continue;
        const std::string rest = mark.text.substr(kCouplingNote.size());
        double stiffness = 0.0;
        if (tune::parse_log_number(rest.substr(0, rest.find(' ')), stiffness) && stiffness > 0.0) {
            changes.push_back({mark.row, stiffness});
            source = "the log's preamble and its coupling marks";
        }
    }
    return changes;
}

/// "grows" when the oscillation's growth fitted over every judged window exceeds the
/// threshold, "decays" when it falls faster than it, else "steady". (An approach to a wall
/// in the judged span also rises from the floor: judge from where the motion settles.)
std::string verdict(const tune::OscillationTrend& trend, double threshold_per_s) {
    if (trend.growth_per_s > threshold_per_s) return "grows";
    return trend.growth_per_s < -threshold_per_s ? "decays" : "steady";
}

int run_plot_run(const PlotRunOptions& o) {
    if (!o.look.out.empty()) check_chart_output(o.look);  // without --out: the judgement only
    tune::TelemetryLog log;
    try {
        log = tune::read_telemetry_log(o.log_path);
    } catch (const tune::LogFormatError& e) {
        std::cerr << "haptic-tune: bad log: " << e.what() << '\n';
        return kExitBadInput;
    }
    if (o.axis >= log.axes) {
        throw UsageError("--axis " + std::to_string(o.axis) + ": " + o.log_path + " has " +
                         std::to_string(log.axes) + " axes (allowed 0.." +
                         std::to_string(log.axes - 1) + ")");
    }
    if (log.rows() < 3) throw UsageError(o.log_path + ": fewer than 3 rows, nothing to judge");
    const std::string axis = std::to_string(o.axis);
    const std::vector<double>& t = required_column(log, "t_s");
    const std::vector<double>& x = required_column(log, "x" + axis + "_m");
    const std::vector<double>& f = required_column(log, "f" + axis + "_n");
    const double period_s = median_period_s(t);
    if (!(period_s > 0.0)) throw UsageError(o.log_path + ": t_s does not increase");

    const auto first = static_cast<std::size_t>(
        std::lower_bound(t.begin(), t.end(), t.front() + o.judge_from_s) - t.begin());
    const auto window = static_cast<std::size_t>(std::max(2.0, std::round(o.window_s / period_s)));
    const double count_m = smallest_step_m(x);
    const double floor_m =
        o.floor_m.value_or(count_m > 0.0 ? kFloorCounts * count_m : kFallbackFloorM);
    const tune::OscillationTrend trend =
        tune::oscillation_trend(x, period_s, first, window, floor_m);

    nlohmann::ordered_json chart = {{"kind", "run"}, {"axis", o.axis}};
    chart["position"] = chart_series(t, x);
    if (const std::vector<double>* xe = log.column("xe" + axis + "_m")) {
        chart["tool"] = chart_series(t, *xe);
    }
    chart["force"] = chart_series(t, f);
    std::string stiffness_source;
    const std::vector<StiffnessChange> stiffness_changes =
        coupling_stiffness(o, log, stiffness_source);
    const bool stiffness = !stiffness_changes.empty();
    const double initial_stiffness_n_per_m =
        stiffness ? stiffness_changes.front().stiffness_n_per_m : 0.0;
    double peak_coupling_energy_j = 0.0;
    if (stiffness) {
        std::vector<double> k_n_per_m(log.rows(), 0.0);
        for (const StiffnessChange& change : stiffness_changes) {
            std::fill(k_n_per_m.begin() +
                          static_cast<std::ptrdiff_t>(std::min(change.from_row, k_n_per_m.size())),
                      k_n_per_m.end(), change.stiffness_n_per_m);
        }
        std::vector<double> energy(log.rows(), 0.0);
        for (int a = 0; a < log.axes; ++a) {
            const std::vector<double>* xa = log.column("x" + std::to_string(a) + "_m");
            const std::vector<double>* xea = log.column("xe" + std::to_string(a) + "_m");
            if (xa == nullptr || xea == nullptr) continue;
            for (std::size_t i = 0; i < energy.size(); ++i) {
                const double stretch_m = (*xa)[i] - (*xea)[i];
                energy[i] += 0.5 * k_n_per_m[i] * stretch_m * stretch_m;
            }
        }
        peak_coupling_energy_j = *std::max_element(energy.begin(), energy.end());
        chart["coupling_energy"] = chart_series(t, energy);
        chart["coupling_stiffness_n_per_m"] = initial_stiffness_n_per_m;
    }
    if (const std::vector<double>* energy = log.column("energy_j")) {
        chart["observer_energy"] = chart_series(t, *energy);
    }

    nlohmann::ordered_json fault_events = nlohmann::ordered_json::array();
    nlohmann::ordered_json marks = nlohmann::ordered_json::object();
    nlohmann::ordered_json flag_counts = nlohmann::ordered_json::object();
    if (const std::vector<double>* faults = log.column("faults")) {
        std::uint32_t before = 0;
        for (std::size_t i = 0; i < faults->size(); ++i) {
            const auto now = static_cast<std::uint32_t>((*faults)[i]);
            servo::for_each_fault(now & ~before, [&](std::string_view name) {
                fault_events.push_back({{"t_s", t[i]}, {"fault", name}});
            });
            before = now;
        }
    }
    if (const std::vector<double>* flags = log.column("tick_flags")) {
        for (const auto& [flag, name] : kMarkedFlags) {
            std::vector<double> at_s;
            std::size_t count = 0;
            for (std::size_t i = 0; i < flags->size(); ++i) {
                if ((static_cast<std::uint32_t>((*flags)[i]) & flag) == 0u) continue;
                ++count;
                if (at_s.size() < kMaxMarks) at_s.push_back(t[i]);
            }
            flag_counts[name] = count;
            if (count > 0) marks[name] = at_s;
        }
    }
    chart["faults"] = fault_events;
    chart["marks"] = marks;
    const std::string judged = verdict(trend, o.growth_threshold_per_s);
    chart["judgement"] = {{"from_s", t[std::min(first, t.size() - 1)]},
                          {"window_s", trend.window_s},
                          {"growth_per_s", trend.growth_per_s},
                          {"verdict", judged}};
    chart["title"] = "Run " + o.log_path + ", axis " + axis + ": the oscillation " + judged +
                     " (growth fitted from " + number_text(t[std::min(first, t.size() - 1)], 3) +
                     " s: " + number_text(trend.growth_per_s, 3) + " /s)";
    chart["caption"] =
        "haptic-tune plot-run; " + o.log_path + ", " + std::to_string(log.rows()) + " ticks at " +
        number_text(1.0 / period_s, 4) + " Hz" +
        (stiffness ? "; k_c = " + number_text(initial_stiffness_n_per_m, 4) + " N/m" : "") +
        "; hapticd " + install::kVersion;
    if (!o.look.out.empty()) render_chart(chart, o.look);

    nlohmann::ordered_json summary = {
        {"log", o.log_path},
        {"chart", o.look.out},
        {"rows", log.rows()},
        {"duration_s", t.back() - t.front()},
        {"rate_hz", 1.0 / period_s},
        {"axes", log.axes},
        {"axis", o.axis},
        {"verdict", judged},
        {"growth_per_s", trend.growth_per_s},
        {"rise_growth_per_s", trend.rise_growth_per_s},
        {"first_amplitude_m", trend.first_amplitude_m},
        {"peak_amplitude_m", trend.peak_amplitude_m},
        {"last_amplitude_m", trend.last_amplitude_m},
        {"windows", trend.amplitude_m.size()},
        {"window_s", trend.window_s},
        {"floor_m", floor_m},
        {"floor_source", o.floor_m       ? "--floor"
                         : count_m > 0.0 ? "3 counts of the smallest position step"
                                         : "1e-6 m: the position never steps"},
        {"faults", fault_events},
        {"flag_counts", flag_counts},
    };
    if (stiffness) {
        summary["coupling_stiffness_n_per_m"] = initial_stiffness_n_per_m;
        summary["coupling_stiffness_source"] = stiffness_source;
        if (stiffness_changes.size() > 1) {
            nlohmann::ordered_json changes = nlohmann::ordered_json::array();
            for (const StiffnessChange& change : stiffness_changes) {
                changes.push_back({{"from_t_s", t[std::min(change.from_row, t.size() - 1)]},
                                   {"stiffness_n_per_m", change.stiffness_n_per_m}});
            }
            summary["coupling_stiffness_changes"] = changes;
        }
        summary["peak_coupling_energy_j"] = peak_coupling_energy_j;
    } else {
        summary["coupling_energy"] =
            "not drawn: the log's preamble names no k_c; give --stiffness, or --config with "
            "[coupling] stiffness";
    }
    print_result(summary, o.look.json);
    return kExitOk;
}

}  // namespace

void add_plot_run_command(CLI::App& app, Invocation& invocation) {
    auto options = std::make_shared<PlotRunOptions>();
    CLI::App* command = app.add_subcommand(
        "plot-run",
        "Chart a recorded run (position, tool, force, the coupling's energy, the passivity "
        "observer, faults) and judge its oscillation: does it grow or die out, and how fast");
    command->add_option("LOG", options->log_path, "telemetry CSV (hapticd --log, hapticctl record)")
        ->required();
    add_chart_look_options(*command, options->look);
    command->get_option("--out")->description(
        "chart file to write: .png, .svg (text kept as text) or .pdf (default: none, the "
        "judgement only)");
    command->get_option("--json")->description("print the judgement as JSON");
    command->add_option("--axis", options->axis, "the axis to chart and judge (default 0)")
        ->check(CLI::Range(0, 63));
    command
        ->add_option("--stiffness", options->stiffness_n_per_m,
                     "coupling stiffness k_c (N/m) for the coupling's energy; default [coupling] "
                     "stiffness from --config, else the log's own preamble and coupling marks")
        ->check(positive_finite("N/m"));
    command->add_option("--config", options->config_path, "the run's hapticd config (for k_c)");
    command
        ->add_option("--from", options->judge_from_s,
                     "judge the oscillation from this many seconds after the log's start "
                     "(default 0.2: after the soft start's wait)")
        ->check(non_negative_finite("s"));
    command
        ->add_option("--window", options->window_s,
                     "length of the windows the amplitude is measured in, s; at least 1.5 "
                     "periods of the slowest oscillation (default 0.1)")
        ->check(positive_finite("s"));
    command
        ->add_option("--floor", options->floor_m,
                     "amplitude floor, m peak to peak (default 3 encoder counts: 3 times the "
                     "smallest step between the log's positions)")
        ->check(positive_finite("m"));
    command
        ->add_option("--growth-threshold", options->growth_threshold_per_s,
                     "a fitted growth beyond this (1/s) is 'grows', below its negative "
                     "'decays' (default 0.5)")
        ->check(positive_finite("1/s"));
    command->callback(
        [options, &invocation] { invocation.run = [options] { return run_plot_run(*options); }; });
}

}  // namespace hapticd::tools
