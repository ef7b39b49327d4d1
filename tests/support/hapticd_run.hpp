// Runs the real hapticd executable on a config and a scene in a scratch directory and
// collects what it leaves behind: the exit code, its messages, the JSON summary and the
// telemetry CSV. Lockstep by default: virtual time, deterministic, about 1 us per tick.
#pragma once

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"

namespace hapticd::testing {

// NOLINTNEXTLINE(bugprone-exception-escape): nlohmann::json's noexcept move is reported as throwing
struct DaemonRun {
    int exit_code = -1;
    std::string out;         ///< hapticd's standard output
    std::string err;         ///< its messages (standard error)
    nlohmann::json summary;  ///< summary.json; null if hapticd wrote none
    TelemetryLog log;        ///< run.csv; empty if hapticd wrote none
    std::string log_header;  ///< the CSV's header row (after the preamble), verbatim
};

struct RunRequest {
    std::string config_toml{};  ///< written to cfg.toml
    std::string scene_toml{};   ///< written to scene.toml (the config names it); empty: none
    double duration_s = 1.0;    ///< --duration: virtual seconds in lockstep; <= 0: none
    bool lockstep = true;       ///< --lockstep
    bool identify = false;      ///< --identify: the excitation run (it ends by itself)
    bool with_log = true;       ///< --log run.csv
    /// NAME=value pairs in hapticd's environment (NOTIFY_SOCKET, WATCHDOG_USEC, ...).
    std::vector<std::pair<std::string, std::string>> environment{};
};

inline DaemonRun run_hapticd(const ScratchDir& dir, const RunRequest& request) {
    const std::string config = dir.write("cfg.toml", request.config_toml);
    if (!request.scene_toml.empty()) dir.write("scene.toml", request.scene_toml);
    const std::string log = dir.file("run.csv");
    const std::string summary = dir.file("summary.json");
    std::ostringstream command;
    command.precision(17);
    for (const auto& [name, value] : request.environment) {
        command << name << "=" << shell_quote(value) << " ";
    }
    command << shell_quote(HAPTICD_BIN) << (request.identify ? " --identify" : "")
            << (request.lockstep ? " --lockstep" : "") << " --no-status";
    if (request.duration_s > 0.0) command << " --duration " << request.duration_s;
    command << " --config " << shell_quote(config) << " --summary " << shell_quote(summary);
    if (request.with_log) command << " --log " << shell_quote(log);
    const CommandResult result = run_command(command.str());
    DaemonRun run;
    run.exit_code = result.exit_code;
    run.out = result.out;
    run.err = result.err;
    if (std::filesystem::exists(summary)) {
        std::ifstream in(summary);
        run.summary = nlohmann::json::parse(in);
    }
    if (std::filesystem::exists(log)) {
        std::ifstream in(log);
        while (std::getline(in, run.log_header) && run.log_header.starts_with('#')) {
        }
        run.log = read_telemetry(log);
    }
    return run;
}

/// The summary's fault names, joined for messages ("" when none).
inline std::string fault_list(const DaemonRun& run) {
    std::string names;
    if (!run.summary.contains("faults")) return "<no summary>";
    for (const auto& name : run.summary.at("faults")) {
        names += (names.empty() ? "" : ",") + name.get<std::string>();
    }
    return names;
}

}  // namespace hapticd::testing
