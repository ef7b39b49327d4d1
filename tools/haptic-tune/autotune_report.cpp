#include "autotune_report.hpp"

#include <algorithm>
#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "hapticd/servo/io.hpp"
#include "hapticd/tune/result_json.hpp"

namespace hapticd::tools {
namespace {

/// The axis as haptic-tune identify prints it (tune::to_json), with its bound and check.
nlohmann::ordered_json axis_json(const tune::AutotuneAxis& a) {
    nlohmann::ordered_json json = a.identified;
    json["bound"] = {{"stiffness", a.bound.coupling.stiffness_n_per_m},
                     {"stiffness_std_error", a.bound_stiffness_std_error_n_per_m},
                     {"damping", a.bound.coupling.damping_n_s_per_m},
                     {"binding_frequency_hz", a.bound.binding_frequency_hz}};
    json["exact_check"] = a.exact;
    return json;
}

}  // namespace

nlohmann::ordered_json outcome_json(const Outcome& o) {
    const tune::AutotuneResult& r = o.result;
    nlohmann::ordered_json axes = nlohmann::ordered_json::array();
    for (const tune::AutotuneAxis& a : r.axes) axes.push_back(axis_json(a));
    nlohmann::ordered_json changes = nlohmann::ordered_json::array();
    for (const daemon::ConfigChange& c : o.changes) {
        changes.push_back({{"table", c.table},
                           {"key", c.key},
                           {"old", c.old_text.empty() ? nlohmann::ordered_json(nullptr)
                                                      : nlohmann::ordered_json(c.old_text)},
                           {"new", c.new_text},
                           {"changed", c.old_text != c.new_text}});
    }
    nlohmann::ordered_json out = {
        {"config", o.config_path},
        {"log", o.log_kept ? nlohmann::ordered_json(o.log_path) : nlohmann::ordered_json(nullptr)},
        {"written", !o.backup_path.empty()},
        {"written_file", o.written_path.empty() ? nlohmann::ordered_json(nullptr)
                                                : nlohmann::ordered_json(o.written_path)},
        {"dry_run", o.dry_run},
        {"backup", o.backup_path.empty() ? nlohmann::ordered_json(nullptr)
                                         : nlohmann::ordered_json(o.backup_path)},
        {"verified", r.verified},
        {"model", "passive"},
        {"rate_hz", r.rate_hz},
        {"delay_s", r.delay_periods / r.rate_hz},
        {"delay_source", to_string(o.delay.source)},
        {"delay_measurement",
         [&]() -> nlohmann::ordered_json {
             if (!o.delay.measurement) return nullptr;
             const daemon::DiagReport& m = *o.delay.measurement;
             if (!m.delay_measured) return {{"measured", false}, {"missing", m.delay_missing}};
             return {{"measured", true},       {"commands", m.delay_commands},
                     {"p50_s", m.delay_s.p50}, {"p99_s", m.delay_s.p99},
                     {"max_s", m.delay_s.max}, {"recommended_s", m.recommended_delay_s}};
         }()},
        {"margin", r.margin},
        {"optimize_damping", r.optimize_damping},
        {"binding_axis", r.binding().identified.axis},
        {"device", r.device},
        {"bound",
         {{"stiffness", r.bound.stiffness_n_per_m},
          {"stiffness_std_error", r.binding().bound_stiffness_std_error_n_per_m},
          {"damping", r.bound.damping_n_s_per_m},
          {"binding_frequency_hz", r.binding().bound.binding_frequency_hz}}},
        {"stiffness", r.coupling.stiffness_n_per_m},
        {"damping", r.coupling.damping_n_s_per_m},
        {"exact_check",
         [&] {
             nlohmann::ordered_json e = r.axes[static_cast<std::size_t>(r.worst_axis)].exact;
             e["stable"] = r.verified;
             e["worst_axis"] = r.axes[static_cast<std::size_t>(r.worst_axis)].identified.axis;
             return e;
         }()},
        {"verdict", r.verdict},
        {"axes", axes},
        {"changes", changes},
        {"startup_check", o.startup ? nlohmann::ordered_json(o.startup->describe())
                                    : nlohmann::ordered_json(nullptr)},
        {"warnings", r.warnings},
        {"solve_time_s", r.solve_time_s},
    };
    return out;
}

void print_text(const Outcome& o) {
    const tune::AutotuneResult& r = o.result;
    const tune::IdentifiedAxis& first = r.axes.front().identified;
    std::cout << "identified from " << (o.log_kept ? o.log_path : "the identification run") << " ("
              << number_text(first.duration_s, 4) << " s at " << number_text(first.rate_hz, 6)
              << " Hz, " << servo::axes_text(static_cast<int>(r.axes.size()))
              << "), value +- standard error:\n";
    for (const tune::AutotuneAxis& a : r.axes) {
        const tune::IdentifiedAxis& id = a.identified;
        std::cout << "  axis " << id.axis << ": mass " << number_text(id.estimate.mass_kg) << " +- "
                  << number_text(id.std_error.mass_kg, 2) << " kg, damping "
                  << number_text(id.estimate.damping_n_s_per_m) << " +- "
                  << number_text(id.std_error.damping_n_s_per_m, 2) << " N s/m, coulomb "
                  << number_text(id.estimate.coulomb_n, 3) << " +- "
                  << number_text(id.std_error.coulomb_n, 2) << " N, offset "
                  << number_text(id.estimate.offset_n, 3) << " +- "
                  << number_text(id.std_error.offset_n, 2) << " N\n";
    }
    std::cout << o.delay.note << '\n';
    std::cout << "largest stable coupling (passive model, "
              << (r.optimize_damping ? "optimised damping" : "b_c = 0") << ", [servo] rate_hz "
              << number_text(r.rate_hz) << " Hz, loop delay "
              << number_text(r.delay_periods / r.rate_hz * 1e3) << " ms):\n";
    for (const tune::AutotuneAxis& a : r.axes) {
        std::cout << "  axis " << a.identified.axis << ": k_c "
                  << number_text(a.bound.coupling.stiffness_n_per_m) << " +- "
                  << number_text(a.bound_stiffness_std_error_n_per_m, 2) << " N/m";
        if (r.optimize_damping) {
            std::cout << " with b_c " << number_text(a.bound.coupling.damping_n_s_per_m)
                      << " N s/m";
        }
        std::cout << (a.bound.binding_frequency_hz > 0.0
                          ? ", binding at " + number_text(a.bound.binding_frequency_hz, 4) + " Hz"
                          : ", binding as f -> 0")
                  << (&a == &r.binding() && r.axes.size() > 1 ? "  <- binding axis" : "") << '\n';
    }
    std::cout << "coupling: margin " << number_text(r.margin) << " x "
              << number_text(r.bound.stiffness_n_per_m) << " N/m = k_c "
              << number_text(r.coupling.stiffness_n_per_m) << " N/m, b_c "
              << number_text(r.coupling.damping_n_s_per_m) << " N s/m\n";
    std::cout << (r.verified ? "verified: " : "REJECTED: ") << r.verdict << '\n';
    if (o.startup)
        std::cout << "start-up check of the edited config: " << o.startup->describe() << '\n';
    for (const std::string& warning : r.warnings) std::cout << "warning: " << warning << '\n';
    if (!o.changes.empty()) {
        std::cout << (o.backup_path.empty() ? "changes (not written):\n" : "changes:\n");
        std::size_t width = 0;
        for (const daemon::ConfigChange& c : o.changes) {
            width = std::max(width, c.table.size() + c.key.size() + 5);
        }
        for (const daemon::ConfigChange& c : o.changes) {
            std::cout << "  " << std::left << std::setw(static_cast<int>(width))
                      << "[" + c.table + "] " + c.key << (c.old_text.empty() ? "(new)" : c.old_text)
                      << " -> " << c.new_text << (c.old_text == c.new_text ? "  (unchanged)" : "")
                      << '\n';
        }
    }
    if (!o.backup_path.empty()) {
        std::cout << "written: " << o.config_path
                  << (o.written_path != o.config_path ? " (" + o.written_path + "; " : " (")
                  << "backup: " << o.backup_path << ")\n";
    } else if (o.dry_run) {
        std::cout << "dry run: " << o.config_path << " not written\n";
    }
}

}  // namespace hapticd::tools
