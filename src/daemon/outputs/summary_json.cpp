#include "outputs/summary_json.hpp"

#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hapticd/tune/result_json.hpp"
#include "outputs/percentiles_json.hpp"

namespace hapticd::daemon {

std::string summary_json(const servo::Summary& s, const RunContext& c) {
    nlohmann::ordered_json j;
    j["version"] = c.stamp.version;
    j["started_at"] = c.stamp.started_at;
    j["host"] = c.stamp.host;
    j["name"] = c.name;
    j["ticks"] = s.ticks;
    j["overruns"] = s.overruns;
    j["missed_periods"] = s.missed_periods;
    j["rate_hz"] = s.rate_hz;
    j["wake_latency_us"] = percentiles_json<nlohmann::ordered_json>(s.wake_latency_us);
    j["tick_compute_us"] = percentiles_json<nlohmann::ordered_json>(s.tick_compute_us);
    j["max_force_n"] = s.max_force_n;
    j["faults"] = s.faults;
    if (s.overrun_budget) {
        const servo::OverrunBudgetBreach& b = *s.overrun_budget;
        j["overrun_budget"] = {{"late_ms", b.late_ms},
                               {"missed_periods", b.missed_periods},
                               {"consecutive_overruns", b.consecutive_overruns},
                               {"max_missed_periods", b.max_missed_periods},
                               {"max_consecutive_overruns", b.max_consecutive_overruns}};
    }
    j["intervals_unknown"] = s.intervals_unknown;
    j["link_recoveries"] = s.link_recoveries;
    j["telemetry_dropped"] = s.telemetry_dropped;
    j["telemetry_records"] = c.telemetry_records;
    if (!c.telemetry_log.empty()) {
        j["telemetry_records_written"] = c.telemetry_records_written;
        j["telemetry_complete"] = c.telemetry_complete;
    }
    j["read_timeouts"] = s.read_timeouts;
    j["solver_not_converged"] = s.solver_not_converged;
    j["saturated_ticks"] = s.saturated_ticks;
    j["passivity_energy_j"] = s.passivity_energy_j;
    j["flight_records"] = c.flight_records;
    j["flight_records_not_written"] = c.flight_records_not_written;
    j["flight_records_complete"] = c.flight_records_complete;
    j["recordings"] = nlohmann::ordered_json::array();
    for (const RecordedFile& file : c.recordings) {
        nlohmann::ordered_json entry{{"path", file.path},
                                     {"records", file.records},
                                     {"dropped", file.dropped},
                                     {"complete", file.complete}};
        if (!file.complete) entry["failure"] = file.failure;
        j["recordings"].push_back(entry);
    }
    j["identify"] = nlohmann::ordered_json::array();
    for (const PlayedExcitation& run : c.excitations) {
        j["identify"].push_back(
            {{"path", run.path}, {"outcome", run.outcome}, {"complete", run.complete}});
    }
    j["exit"] = c.exit;
    j["state"] = c.final_state;
    if (!c.stopped_by.empty()) j["stopped_by"] = c.stopped_by;
    if (!c.environment_failure.empty()) j["environment_failure"] = c.environment_failure;
    if (c.external_world.external) {
        const servo::EnvironmentPortReport& w = c.external_world;
        j["external_world"] = {{"updates", w.update},
                               {"stale_episodes", w.stale_episodes},
                               {"rejected_updates", w.rejected_updates},
                               {"energy_j", w.energy_j},
                               {"energy_removed_j", w.energy_removed_j}};
    }
    if (!c.final_command.empty()) j["final_command"] = c.final_command;
    j["run_time_s"] = c.run_time_s;
    j["lockstep"] = c.lockstep;
    j["config"] = c.config_source;
    j["config_path"] = nullptr;  // the embedded default
    if (!c.config_path.empty()) j["config_path"] = c.config_path;
    j["device"] = c.device;
    j["scene"] = {{"name", c.scene}, {"causality", c.causality}};
    // The start-up check's verdict as haptic-tune check prints it (tune/result_json.hpp); a
    // check that was skipped names only its model ("off", or why there is none).
    if (c.check.skipped) {
        j["stability_check"] = {{"model", c.check.model_name()}};
    } else {
        j["stability_check"] = static_cast<const tune::StabilityVerdict&>(c.check);
    }
    j["realtime"] = {
        {"mode", std::string(servo::to_string(c.realtime.mode))},
        {"sched_fifo", c.realtime.scheduler_fifo},
        {"priority", c.realtime.priority},
        {"memory_locked", c.realtime.memory_locked},
        {"cpu", c.realtime.cpu},
        {"affinity_set", c.realtime.affinity_set},
        {"other_threads_cpus", c.other_threads.off_servo_cpu ? c.other_threads.cpus : ""},
        {"other_threads_not_off", c.other_threads.why_not},
        {"cpu_dma_latency_held", c.realtime.cpu_dma_latency_held},
        {"refused", c.realtime.refused}};
    return j.dump(2);
}

std::string summary_text(const servo::Summary& s, const RunContext& c) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(1);
    out << "hapticd summary: " << s.ticks << " ticks at " << s.rate_hz << " Hz over "
        << std::setprecision(3) << c.run_time_s << " s" << (c.lockstep ? " (lockstep)" : "")
        << ", exit: " << c.exit << (c.stopped_by.empty() ? "" : " (" + c.stopped_by + ")") << "\n";
    out << std::setprecision(1) << "  wake latency us: p50 " << s.wake_latency_us.p50 << ", p99 "
        << s.wake_latency_us.p99 << ", p99.9 " << s.wake_latency_us.p999 << ", max "
        << s.wake_latency_us.max << "\n";
    out << std::setprecision(2) << "  tick compute us: p50 " << s.tick_compute_us.p50 << ", p99 "
        << s.tick_compute_us.p99 << ", max " << s.tick_compute_us.max << "\n";
    out << "  overruns " << s.overruns << " (" << s.missed_periods << " periods missed), max force "
        << s.max_force_n << " N, telemetry dropped " << s.telemetry_dropped << "\n";
    if (!c.telemetry_log.empty()) {
        out << "  telemetry: " << c.telemetry_records_written << " of " << c.telemetry_records
            << " records written to " << c.telemetry_log
            << (c.telemetry_complete ? "" : " (INCOMPLETE)") << "\n";
    }
    for (const RecordedFile& file : c.recordings) {
        out << "  recorded: " << file.path << ", " << file.records << " records"
            << (file.complete ? "" : " (INCOMPLETE: " + file.failure + ")") << "\n";
    }
    for (const PlayedExcitation& run : c.excitations) {
        out << "  identify: " << run.outcome << "\n";
    }
    out << "  faults:";
    if (s.faults.empty()) out << " none";
    for (const std::string& fault : s.faults) out << " " << fault;
    if (s.link_recoveries > 0) out << " (link recoveries: " << s.link_recoveries << ")";
    out << "\n";
    if (s.overrun_budget) out << "  overrun_budget: " << servo::describe(*s.overrun_budget) << "\n";
    if (s.solver_not_converged > 0) {
        out << "  the coupling's series solve (17) failed on " << s.solver_not_converged
            << " ticks (the tool's balance was not met: the scene may be too stiff, or too "
               "negatively stiff, for the coupling)\n";
    }
    if (s.intervals_unknown > 0) {
        out << "  samples with an unknown interval (zero force, history restarted): "
            << s.intervals_unknown << "\n";
    }
    return out.str();
}

}  // namespace hapticd::daemon
