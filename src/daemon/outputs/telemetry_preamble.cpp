// The preamble of a log or a recording (telemetry_writer.hpp, docs/daemon.md "Telemetry").
#include <sstream>

#include "hapticd/daemon/telemetry_writer.hpp"
#include "hapticd/input/printable.hpp"
#include "hapticd/input/range.hpp"

namespace hapticd::daemon {

std::string telemetry_preamble(const TelemetryHeader& header) {
    std::ostringstream out;
    const auto line = [&out](std::string_view key, std::string_view value) {
        out << "# " << key << ": " << input::printable(value) << "\n";
    };
    out << "# hapticd telemetry: the columns, the status, flag and fault bits and these lines "
           "are in docs/daemon.md, \"Telemetry\"\n";
    line("version", header.version);
    if (!header.name.empty()) line("name", header.name);
    line("started", header.started_at);
    line("host", header.host);
    line("device", header.device);
    line("config", header.config);
    line("config_sha256", header.config_sha256);
    line("rate_hz", input::exact_number(header.rate_hz));
    if (header.coupling_enabled) {
        line("coupling_stiffness_n_per_m", input::exact_number(header.stiffness_n_per_m));
        line("coupling_damping_n_s_per_m", input::exact_number(header.damping_n_s_per_m));
    } else {
        line("coupling", "off ([coupling] enabled = false: the handle is the tool)");
    }
    line("stability", header.stability);
    line("scene", header.scene);
    return out.str();
}

}  // namespace hapticd::daemon
