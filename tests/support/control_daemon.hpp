// A hapticd with a control socket, driven by the real hapticctl: what the control socket's HIL
// tests (control_socket_test.cpp, scene_load_test.cpp) start and ask.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>

#include "background_daemon.hpp"
#include "default_config.hpp"
#include "hapticd_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {

/// A whole config's text, for Daemon.
struct ConfigText {
    std::string toml;
};

/// A hapticd with a control socket (real time, on the sim), until stop().
struct Daemon {
    /// On the default config with room (config_with_room), `extra_toml` appended.
    Daemon(const ScratchDir& dir, const std::string& name, const std::string& extra_toml = "")
        : Daemon(dir, name, ConfigText{config_with_room(extra_toml)}) {}
    Daemon(const ScratchDir& dir, const std::string& name, const ConfigText& config)
        : Daemon(dir, name, config, dir.file(name + ".sock")) {}
    /// Serving the socket at `socket_path` (an instance's, instance_socket()).
    Daemon(const ScratchDir& dir, const std::string& name, const ConfigText& config,
           std::string socket_path)
        : socket(std::move(socket_path)),
          summary(dir.file(name + "-summary.json")),
          process(HAPTICD_BIN,
                  {"--no-status", "--config", dir.write(name + ".toml", config.toml), "--socket",
                   socket, "--summary", summary},
                  dir.file(name + ".err")) {}
    std::string socket;
    std::string summary;
    BackgroundDaemon process;
};

/// Where hapticd@NAME serves its control socket, which `hapticctl -i NAME` asks:
/// /run/hapticd/NAME.sock (the unit's RuntimeDirectory=hapticd; docs/install.md).
inline std::string instance_socket(const std::string& name) {
    return "/run/hapticd/" + name + ".sock";
}

/// hapticctl -i NAME ARGUMENTS.
inline CommandResult hapticctl_instance(const std::string& name, const std::string& arguments) {
    return run_command(shell_quote(HAPTICCTL_BIN) + " -i " + shell_quote(name) + " " + arguments);
}

inline CommandResult hapticctl(const std::string& socket, const std::string& arguments) {
    return run_command(shell_quote(HAPTICCTL_BIN) + " --socket " + shell_quote(socket) + " " +
                       arguments);
}

inline nlohmann::json status_of(const std::string& socket) {
    const CommandResult r = hapticctl(socket, "status --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

// Polls status until `done(status)` or `timeout`; returns the last status.
template <typename Done>
nlohmann::json status_when(const std::string& socket, Done done,
                           std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    nlohmann::json s = status_of(socket);
    while (!s.is_null() && !done(s) && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        s = status_of(socket);
    }
    return s;
}

inline bool armed_state(const nlohmann::json& s) {
    return s["state"] == "arming" || s["state"] == "running";
}

}  // namespace hapticd::testing
