#include "status_text.hpp"

#include <cstdint>
#include <iomanip>
#include <sstream>

namespace hapticd::ctl {
namespace {

std::string vector_text(const nlohmann::json& v, double scale) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << "[";
    for (std::size_t i = 0; i < v.size(); ++i) {
        out << (i == 0 ? "" : " ") << v[i].get<double>() * scale;
    }
    out << "]";
    return out.str();
}

std::string faults_text(const nlohmann::json& faults) {
    if (faults.empty()) return "none";
    std::string text;
    for (const auto& fault : faults) text += (text.empty() ? "" : ",") + fault.get<std::string>();
    return text;
}

/// The device's link counts, one line, when it keeps them (a daemon before them sends no
/// `counted`): "frames    12000 sent, 11998 received, 2 bad, 1 reply timeouts, ...". The
/// last three came with plugin ABI 5: a daemon still running an earlier release (an upgrade
/// restarts no instance) sends none, and the line leaves them out.
std::string device_link_text(const nlohmann::json& link) {
    if (!link.value("counted", false)) return "";
    const auto count = [&link](const char* name) { return link.at(name).get<std::uint64_t>(); };
    const auto later = [&link, &count](const char* name, const char* what) {
        return link.contains(name) ? ", " + std::to_string(count(name)) + what : std::string();
    };
    std::ostringstream out;
    out << "frames    " << count("frames_sent") << " sent, " << count("frames_received")
        << " received, " << count("bad_frames") << " bad, " << count("transfer_errors")
        << " transfer errors, " << count("reply_timeouts") << " reply timeouts, "
        << count("missed_samples") << " samples missed, " << count("late") << " late, "
        << count("duplicate") << " duplicate, " << count("device_errors") << " device errors, "
        << count("disconnects") << " disconnects, " << count("reconnects") << " reconnects"
        << later("wrong_session", " of another session") << later("unexpected", " unexpected")
        << later("out_of_step", " out of step") << "\n";
    return out.str();
}

}  // namespace

std::string status_text(const nlohmann::json& s) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(1);
    // [servo] name; the daemon's reader refused control characters in it, and hapticctl's
    // stdout filters them besides (PrintableFilter).
    if (const auto name = s.find("name"); name != s.end() && !name->get<std::string>().empty()) {
        out << "name      " << name->get<std::string>() << "\n";
    }
    out << "state     " << s.at("state").get<std::string>();
    if (s.at("state") == "arming") {
        out << " (soft start " << std::setprecision(0)
            << 100.0 * s.at("soft_start_scale").get<double>() << "%)" << std::setprecision(1);
    }
    out << "\n"
        << "tick      " << s.at("tick").get<std::uint64_t>() << " (t " << std::setprecision(2)
        << s.at("t_s").get<double>() << " s)\n"
        << std::setprecision(1) << "rate      " << s.at("measured_rate_hz").get<double>()
        << " Hz over the last second (" << s.at("rate_hz").get<double>() << " Hz set)\n"
        << "x         " << vector_text(s.at("x_m"), 1e3) << " mm\n"
        << "xe        " << vector_text(s.at("xe_m"), 1e3) << " mm\n"
        << "f         " << vector_text(s.at("f_n"), 1.0) << " N\n"
        << "faults    " << faults_text(s.at("faults")) << "\n"
        << "overruns  " << s.at("overruns").get<std::uint64_t>() << "\n"
        << "wake      p50 " << s.at("wake_latency_us").at("p50").get<double>() << " us, p99 "
        << s.at("wake_latency_us").at("p99").get<double>() << " us, max "
        << s.at("wake_latency_us").at("max").get<double>() << " us\n"
        << "compute   p50 " << s.at("tick_compute_us").at("p50").get<double>() << " us, p99 "
        << s.at("tick_compute_us").at("p99").get<double>() << " us, max "
        << s.at("tick_compute_us").at("max").get<double>() << " us\n"
        << "link      " << s.at("link").at("read_timeouts").get<std::uint64_t>()
        << " reads without a sample, " << s.at("link").at("link_recoveries").get<std::uint64_t>()
        << " recoveries\n"
        << device_link_text(s.at("link")) << "device    " << s.at("device").get<std::string>()
        << "\n"
        << "config    " << s.at("config_path").get<std::string>() << "\n";
    if (s.contains("scene") && s["scene"].is_object()) {
        out << "scene     \"" << s["scene"].at("name").get<std::string>() << "\" from "
            << s["scene"].at("source").get<std::string>() << "\n";
    }
    if (s.contains("external_world") && s["external_world"].is_object()) {
        const nlohmann::json& w = s["external_world"];
        out << "world     " << w.at("state").get<std::string>() << ", update "
            << w.at("update").get<std::uint64_t>() << ", stale "
            << w.at("stale_episodes").get<std::uint64_t>() << " times, " << std::setprecision(6)
            << w.at("energy_removed_j").get<double>() << " J removed by the passivity controller"
            << std::setprecision(1);
        if (!w.at("why").get<std::string>().empty()) out << ": " << w.at("why").get<std::string>();
        out << "\n";
    }
    if (s.contains("environment_failure") && s["environment_failure"].is_string()) {
        out << "failure   " << s["environment_failure"].get<std::string>() << "\n";
    }
    if (s.contains("recording") && s["recording"].is_string()) {
        out << "recording " << s["recording"].get<std::string>() << "\n";
    }
    return out.str();
}

std::string watch_line(const nlohmann::json& s) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(2) << "t " << s.at("t_s").get<double>() << " s  "
        << s.at("state").get<std::string>() << "  " << std::setprecision(1)
        << s.at("measured_rate_hz").get<double>() << " Hz  x " << vector_text(s.at("x_m"), 1e3)
        << " mm  f " << vector_text(s.at("f_n"), 1.0) << " N  faults "
        << faults_text(s.at("faults"));
    return out.str();
}

std::string stream_header(int axes) {
    std::string header = "tick,t_s,state";
    for (const char* column : {"x", "xe", "f"}) {
        const std::string unit = std::string(column) == "f" ? "_n" : "_m";
        for (int i = 0; i < axes; ++i)
            header += "," + std::string(column) + std::to_string(i) + unit;
    }
    return header + ",faults";
}

std::string stream_row(const nlohmann::json& event, int axes) {
    std::ostringstream row;
    row << std::setprecision(17) << event.at("tick").get<std::uint64_t>() << ","
        << event.at("t_s").get<double>() << "," << event.at("state").get<std::string>();
    for (const char* column : {"x_m", "xe_m", "f_n"}) {
        const nlohmann::json& values = event.at(column);
        for (int i = 0; i < axes; ++i)
            row << "," << values.at(static_cast<std::size_t>(i)).get<double>();
    }
    std::string faults;
    for (const auto& fault : event.at("faults")) {
        faults += (faults.empty() ? "" : "|") + fault.get<std::string>();
    }
    row << "," << faults;
    return row.str();
}

}  // namespace hapticd::ctl
