// config/hapticd.toml, the default config (the simulated pen display and the demo wall), with
// its scene path made absolute so that it runs from a scratch directory.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "text_file.hpp"

namespace hapticd::testing {

/// The default config; `servo_lines` ("cpu = 1\n") go at the top of its [servo] table.
inline std::string default_config(const std::string& servo_lines = "") {
    std::string config = read_file(HAPTICD_SOURCE_DIR "/config/hapticd.toml");
    const std::string scene = "file = \"scenes/demo-wall.toml\"";
    const std::string servo = "[servo]\n";
    EXPECT_NE(config.find(scene), std::string::npos);
    EXPECT_NE(config.find(servo), std::string::npos);
    config.replace(config.find(scene), scene.size(),
                   "file = \"" HAPTICD_SOURCE_DIR "/config/scenes/demo-wall.toml\"");
    config.replace(config.find(servo), servo.size(), servo + servo_lines);
    return config;
}

/// The default config with an overrun budget that a shared VM's stalls (tens of ms) do not
/// exhaust, for tests that judge something else than whether the host stalled once (the
/// control socket, each instance's rate). `servo_lines` go at the top of its [servo] table.
inline std::string config_with_room(const std::string& extra_toml,
                                    const std::string& servo_lines = "") {
    std::string config = default_config(servo_lines) + extra_toml;
    const std::string safety = "[safety]\n";
    config.replace(config.find(safety), safety.size(),
                   safety + "max_missed_periods = 1000\nmax_consecutive_overruns = 1000\n");
    return config;
}

}  // namespace hapticd::testing
