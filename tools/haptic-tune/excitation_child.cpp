#include "excitation_child.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <vector>

#include "autotune_error.hpp"
#include "child_process.hpp"
#include "hapticd/daemon/device_open.hpp"
#include "hapticd/device/sim/sim_config.hpp"

namespace hapticd::tools {
namespace {

/// What hapticd's exit means (docs/daemon.md's exit codes).
std::string describe_hapticd_exit(const ChildRun& run) {
    if (!run.started() || run.signal != 0) return run.describe_exit();
    switch (run.exit_code) {
        case 1:
            return "exited with status 1: a fault stopped the run, or the handle left the "
                   "[identify] workspace (its message above says which)";
        case 2:
            return "exited with status 2: it refused the config or the command line (its "
                   "message above says why)";
        case 3:
            return "exited with status 3: its telemetry log is incomplete (disk full or a write "
                   "error; its message above says which)";
        default:
            return run.describe_exit();
    }
}

}  // namespace

std::string default_hapticd() {
    std::error_code error;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
    if (!error) {
        const std::filesystem::path beside = self.parent_path() / "hapticd";
        if (::access(beside.c_str(), X_OK) == 0) return beside.string();
    }
    return "hapticd";
}

bool sim_lockstep(const daemon::Config& config) {
    if (config.device.plugin != "sim") return false;
    try {
        // [device.sim] as the sim plugin reads it in open(), from what the daemon hands it.
        return device::sim::parse_sim_config(daemon::device_config(config, /*lockstep=*/false))
                   .clock == device::sim::SimClock::lockstep;
    } catch (const input::ConfigError&) {
        return false;  // hapticd itself will say what is wrong with the table
    }
}

void run_identification(const std::string& hapticd, const std::string& config_path,
                        const std::string& log_path, bool lockstep, bool quiet, bool& started) {
    std::array<int, 2> lifeline{-1, -1};
    if (::pipe2(lifeline.data(), O_CLOEXEC) != 0) {
        throw AutotuneError(std::string("cannot create the lifeline pipe for hapticd: ") +
                            std::strerror(errno));
    }
    std::vector<std::string> args = {hapticd,     "--identify", "--config",
                                     config_path, "--log",      log_path};
    if (lockstep) args.emplace_back("--lockstep");
    if (quiet) args.emplace_back("--no-status");
    std::string command;
    for (const std::string& arg : args) command += (command.empty() ? "" : " ") + arg;
    args.emplace_back("--parent-lifeline");
    args.emplace_back(std::to_string(lifeline[0]));
    std::cerr << "haptic-tune: autotune: running " << command << '\n';

    ChildOptions options;
    options.forward_stop_signals = true;
    options.inherited_fd = lifeline[0];  // hapticd watches the read end; the write end is ours
    const ChildRun run = run_child(args, options);
    started = run.started();
    ::close(lifeline[0]);
    ::close(lifeline[1]);

    if (!run.started()) {
        throw AutotuneError(
            "cannot run " + hapticd +
            " for the identification run: " + std::strerror(run.spawn_error) +
            (hapticd.find('/') == std::string::npos
                 ? " (it is neither next to haptic-tune nor on PATH; give --hapticd PATH, or "
                   "record a run yourself and give --log)"
                 : " (give --hapticd PATH, or record a run yourself and give --log)"));
    }
    if (run.interrupted_by != 0) {
        throw AutotuneError("interrupted by SIG" + std::string(sigabbrev_np(run.interrupted_by)) +
                            ": passed on to the identification run (" + command + "), which " +
                            describe_hapticd_exit(run) +
                            (run.signal == 0 ? " (it stops at zero force)" : "") +
                            "; nothing was written");
    }
    if (!run.succeeded()) {
        throw AutotuneError("the identification run failed: " + command + " " +
                            describe_hapticd_exit(run) + "; nothing was written");
    }
}

}  // namespace hapticd::tools
