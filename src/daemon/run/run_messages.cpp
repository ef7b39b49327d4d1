#include "run/run_messages.hpp"

#include <array>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "hapticd/daemon/journal.hpp"
#include "hapticd/servo/faults.hpp"
#include "run/realtime_advice.hpp"

namespace hapticd::daemon {
namespace {

std::string format_vector_mm(const std::array<double, servo::kMaxAxes>& v, int axes, double scale) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << "[";
    for (int i = 0; i < axes; ++i)
        out << (i == 0 ? "" : " ") << v[static_cast<std::size_t>(i)] * scale;
    out << "]";
    return out.str();
}

}  // namespace

std::string start_line_prefix(const Config& config) {
    // The reader refused control characters in it (input::Text).
    return config.servo.name.empty() ? "hapticd: " : "hapticd: " + config.servo.name + ": ";
}

std::string device_line(const device::DeviceInfo& info) {
    return info.name + " device, " + servo::axes_text(info.axes) + ", " +
           (info.lockstep ? "lockstep" : "real-time") + " clock";
}

std::string status_line(const servo::StatusSnapshot& s, int axes) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << "hapticd: t " << s.t_s << " s  x "
        << format_vector_mm(s.x_m, axes, 1e3) << " mm  xe " << format_vector_mm(s.xe_m, axes, 1e3)
        << " mm  f " << format_vector_mm(s.f_n, axes, 1.0) << " N  ";
    out << servo::servo_state_name(s.state);
    if (s.state == servo::ServoState::arming) {
        out << " " << std::setprecision(0) << 100.0 * s.soft_start_scale << "%";
    }
    out << "  overruns " << s.overruns;
    if (s.solver_not_converged > 0) out << "  solver failed " << s.solver_not_converged << " ticks";
    out << "  faults ";
    if (s.faults == 0u) out << "none";
    bool first = true;
    servo::for_each_fault(s.faults, [&](std::string_view name) {
        out << (first ? "" : ",") << name;
        first = false;
    });
    return out.str();
}

std::string service_status(const servo::StatusSnapshot& s, double rate_hz,
                           std::optional<double> measured_rate_hz, const std::string& note) {
    std::ostringstream out;
    out << servo::servo_state_name(s.state) << ", " << rate_hz << " Hz";
    if (measured_rate_hz) {
        std::ostringstream measured;
        measured << std::fixed << std::setprecision(1) << *measured_rate_hz;
        out << " (measured " << measured.str() << ")";
    }
    out << ", tick " << s.tick << ", overruns " << s.overruns << ", faults "
        << (s.faults == 0u ? std::string("none") : fault_names(s.faults));
    if (!note.empty()) out << ", " << note;
    return out.str();
}

std::string fault_names(std::uint32_t faults) {
    std::string names;
    servo::for_each_fault(faults, [&](std::string_view name) {
        names += (names.empty() ? "" : ",") + std::string(name);
    });
    return names;
}

std::string fault_change_line(std::uint32_t before, const servo::StatusSnapshot& now,
                              const Config& config) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(3) << "hapticd: t " << now.t_s
        << " s: " << std::defaultfloat;
    if (now.faults == 0u && !servo::only_link_faults(before)) {
        out << "fault latch cleared, force returns through the soft start";
        return out.str();
    }
    if (now.faults == 0u) {
        out << "link recovered (the device sent good samples for "
            << config.safety.reconnect.settle_s
            << " s): fault latch cleared, force returns through the soft start";
        return out.str();
    }
    out << "fault " << fault_names(now.faults & ~before) << ", force zeroed";
    if (config.safety.reconnect.enabled && servo::only_link_faults(now.faults)) {
        out << "; waiting for the device to come back";
        if (config.safety.reconnect.timeout_s > 0.0) {
            out << " (at most " << config.safety.reconnect.timeout_s
                << " s, [safety] reconnect_timeout)";
        }
    }
    return out.str();
}

std::string figures_line(const servo::StatusSnapshot& now, const servo::StatusSnapshot& before,
                         double seconds) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(1) << "hapticd: t " << now.t_s
        << " s: " << servo::servo_state_name(now.state) << ", tick " << now.tick << ", "
        << (seconds > 0.0 ? static_cast<double>(now.tick - before.tick) / seconds : 0.0)
        << " Hz over the last " << seconds << " s, overruns " << now.overruns << " (+"
        << now.overruns - before.overruns << ")";
    if (now.solver_not_converged > before.solver_not_converged) {
        out << ", solver failed on " << now.solver_not_converged - before.solver_not_converged
            << " ticks";
    }
    out << ", faults " << (now.faults == 0u ? std::string("none") : fault_names(now.faults));
    return out.str();
}

std::string report_realtime(const servo::RealtimeRequest& request,
                            const servo::RealtimeReport& report, std::ostream& log) {
    std::string note = realtime_refused_note(request, report);
    if (!note.empty()) {
        log << priority::warning << "hapticd: " << report.brief() << ". "
            << realtime_advice(request, report) << "\n"
            << std::flush;
    }
    return note;
}

std::string millimetres(const env::Vec3& v, int axes) {
    std::array<double, servo::kMaxAxes> values{};
    for (int i = 0; i < servo::kMaxAxes; ++i) values[static_cast<std::size_t>(i)] = v[i];
    return format_vector_mm(values, axes, 1e3);
}

}  // namespace hapticd::daemon
