// hapticctl scene FILE against a running hapticd (docs/control.md, "scene_load"): the scene is
// built and checked off the servo thread, rendered from a tick boundary on through the soft
// start, and refused with the reason when the run cannot render it: the other causality, a
// bad file, a detent too stiff for the coupling, or a stability check that fails with the
// gains in force. Coupling requests are then checked against the scene in force.
#include <gtest/gtest.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "config_editor.hpp"
#include "control_daemon.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

namespace hapticd::testing {
namespace {

using namespace std::chrono_literals;

// A wall at x = surface_m with free space on its -x side, as the demo wall at x = 0.
std::string wall_scene(const std::string& name, double surface_m, double stiffness_n_per_m) {
    return "[scene]\nname = \"" + name +
           "\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\noffset = " + std::to_string(-surface_m) +
           "\nstiffness = " + std::to_string(stiffness_n_per_m) + "\n";
}

// The god-object's plane at x = surface_m, free space on its -x side.
std::string proxy_scene(const std::string& name, double surface_m) {
    return "[scene]\nname = \"" + name +
           "\"\naxes = 1\n[[proxy_plane]]\nnormal = [-1.0]\noffset = " +
           std::to_string(-surface_m) + "\n";
}

// The default config with its grasp's push moved past the end of a test: the handle stays
// 1 cm in front of the demo wall however late a slow host gets the scene loaded.
std::string still_grasp_config() {
    std::string config = config_with_room("");
    const std::string push_start = "start = 1.0,";
    config.replace(config.find(push_start), push_start.size(), "start = 600.0,");
    return config;
}

// hapticctl scene FILE, FILE relative to `dir` as a shell user in it would give it.
CommandResult load_scene(const ScratchDir& dir, const std::string& socket,
                         const std::string& file) {
    return run_command("cd " + shell_quote(dir.path().string()) + " && " +
                       shell_quote(HAPTICCTL_BIN) + " --socket " + shell_quote(socket) + " scene " +
                       shell_quote(file));
}

TEST(HilSceneLoad, ASceneLoadedOverTheSocketIsRenderedThroughTheSoftStart) {
    const ScratchDir dir;
    Daemon d(dir, "lab", ConfigText{still_grasp_config()});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    const nlohmann::json before = status_of(d.socket);
    EXPECT_EQ(before["scene"]["name"], "demo-wall") << before.dump();
    // The grasp holds the handle 1 cm in front of the demo wall: no force. A wall 5 mm
    // behind the handle puts it 5 mm deep: 3600 N/m in series with 2000 N/m (1286 N/m)
    // against the grasp's 500 N/m settles at 1286 * 500 / 1786 * 5 mm = 1.8 N.
    const nlohmann::json free = status_when(d.socket, [](const nlohmann::json& s) {
        return s["state"] == "running" && s["t_s"] >= 0.2;
    });
    EXPECT_NEAR(free["f_n"][0].get<double>(), 0.0, 1e-9) << free.dump();
    dir.write("near-wall.toml", wall_scene("near-wall", -0.015, 2000.0));
    const CommandResult loaded = load_scene(dir, d.socket, "near-wall.toml");
    ASSERT_EQ(loaded.exit_code, 0) << loaded.err;
    EXPECT_NE(loaded.out.find("scene \"near-wall\" from " + dir.file("near-wall.toml") +
                              " from the next tick, through the soft start\n"),
              std::string::npos)
        << loaded.out;
    EXPECT_NE(loaded.out.find("stability check (passive model"), std::string::npos) << loaded.out;
    const nlohmann::json after = status_of(d.socket);
    EXPECT_EQ(after["scene"]["name"], "near-wall");
    EXPECT_EQ(after["scene"]["source"], dir.file("near-wall.toml"));
    const nlohmann::json pushed = status_when(d.socket, [](const nlohmann::json& s) {
        return s["state"] == "running" && s["f_n"][0].get<double>() < -1.7;
    });
    EXPECT_EQ(pushed["state"], "running") << pushed.dump();
    EXPECT_LT(pushed["f_n"][0].get<double>(), -1.7) << "the new wall pushes the handle out (-x)";
    EXPECT_GT(pushed["f_n"][0].get<double>(), -2.2) << pushed.dump();
    EXPECT_EQ(pushed["faults"].size(), 0u) << pushed.dump();
    const CommandResult text = hapticctl(d.socket, "status");
    EXPECT_NE(text.out.find("scene     \"near-wall\" from " + dir.file("near-wall.toml")),
              std::string::npos)
        << text.out;

    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    const std::string messages = d.process.messages();
    EXPECT_NE(messages.find("control: scene_load from pid "), std::string::npos) << messages;
    EXPECT_NE(messages.find("scene \"near-wall\" from " + dir.file("near-wall.toml")),
              std::string::npos)
        << messages;
    const nlohmann::json summary = nlohmann::json::parse(read_file(d.summary));
    EXPECT_EQ(summary["scene"]["name"], "near-wall")
        << "the summary names the scene in force at the end";
}

// A run of constraint scenes loads another constraint scene (the god-object's plane 5 mm
// behind the handle: the coupling spring pushes it out), and refuses a penalty scene.
TEST(HilSceneLoad, AnAdmittanceRunLoadsAnAdmittanceSceneAndRefusesAnImpedanceOne) {
    const ScratchDir dir;
    const std::string first = dir.write("proxy-wall.toml", proxy_scene("proxy-wall", 0.0));
    const daemon::EditedConfig config =
        daemon::edit_config_text(config_with_room(""), {{"scene", "file", first}}, "lab.toml");
    Daemon d(dir, "lab", ConfigText{config.text});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    EXPECT_EQ(status_of(d.socket)["scene"]["name"], "proxy-wall");
    dir.write("near-proxy.toml", proxy_scene("near-proxy", -0.015));
    const CommandResult loaded = load_scene(dir, d.socket, "near-proxy.toml");
    ASSERT_EQ(loaded.exit_code, 0) << loaded.err;
    // The handle at -10 mm is 5 mm past the plane: about k_c 5 mm = 18 N before it gives way.
    const nlohmann::json pushed = status_when(d.socket, [](const nlohmann::json& s) {
        return s["state"] == "running" && s["f_n"][0].get<double>() < -2.0;
    });
    EXPECT_LT(pushed["f_n"][0].get<double>(), -2.0) << pushed.dump();
    EXPECT_LT(pushed["xe_m"][0].get<double>(), -0.015 + 1e-9) << "the tool stays on the plane";
    const CommandResult wall =
        load_scene(dir, d.socket, HAPTICD_SOURCE_DIR "/config/scenes/demo-wall.toml");
    EXPECT_EQ(wall.exit_code, 1);
    EXPECT_NE(wall.err.find("is an impedance scene; this run renders admittance scenes"),
              std::string::npos)
        << wall.err;
    EXPECT_EQ(status_of(d.socket)["scene"]["name"], "near-proxy");
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

struct Refusal {
    std::string file;
    std::string text;  ///< written to `file`; empty: none
    std::string says;
};

TEST(HilSceneLoad, WhatTheRunCannotRenderIsRefusedWithTheReasonAndTheSceneKept) {
    const ScratchDir dir;
    Daemon d(dir, "lab");
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    const Refusal cases[] = {
        {"proxy.toml", "[scene]\nname = \"p\"\naxes = 1\n[[proxy_plane]]\nnormal = [-1.0]\n",
         "(scene \"p\") is an admittance scene; this run renders impedance scenes: restart "
         "hapticd with it in [scene] file"},
        {"bad.toml", "[scene]\nname = \"b\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\nstiffness = -5\n",
         "bad.toml:6: [[wall]] #1 stiffness = -5 is out of range"},
        {"three.toml", "[scene]\nname = \"t\"\naxes = 3\n", "axes"},
        {"missing.toml", "", "missing.toml"},
        // -2π 10 N / 10 mm = -6283 N/m between the notches, past -k_c = -3600 N/m.
        {"detent.toml",
         "[scene]\nname = \"d\"\naxes = 1\n[[detent]]\naxis = [1.0]\nperiod = 0.01\n"
         "peak_force = 10.0\n",
         "out of range for this coupling: allowed > -k_c = -3600 N/m"},
    };
    for (const Refusal& c : cases) {
        SCOPED_TRACE(c.file);
        if (!c.text.empty()) dir.write(c.file, c.text);
        const CommandResult r = load_scene(dir, d.socket, c.file);
        EXPECT_EQ(r.exit_code, 1) << r.out;
        EXPECT_NE(r.err.find("scene_load refused: "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    }
    EXPECT_EQ(status_of(d.socket)["scene"]["name"], "demo-wall");
    for (const char* bad : {"scene", "scene a.toml b.toml"}) {
        SCOPED_TRACE(bad);
        EXPECT_EQ(hapticctl(d.socket, bad).exit_code, 2);
    }
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    EXPECT_NE(d.process.messages().find("control: scene_load from pid "), std::string::npos);
}

// One period of delay in [device.model] and the check against the scene's own objects: a
// soft wall (500 N/m) lets k_c = 1600 N/m pass, the demo wall (2e4 N/m) only up to about
// 1333 N/m (docs/stability-models.md, "Scenes"). So what a coupling request may set depends
// on the scene in force, and what scene may be loaded on the gains in force.
TEST(HilSceneLoad, TheStabilityCheckJudgesTheNewSceneAndCouplingsTheSceneInForce) {
    const ScratchDir dir;
    const std::string soft = dir.write("soft-wall.toml", wall_scene("soft-wall", 0.0, 500.0));
    const std::string demo = HAPTICD_SOURCE_DIR "/config/scenes/demo-wall.toml";
    const daemon::EditedConfig config =
        daemon::edit_config_text(config_with_room(""),
                                 {{"device.model", "delay", 0.001},
                                  {"coupling", "stiffness", 1200.0},
                                  {"coupling", "environments", std::string("scene")},
                                  {"scene", "file", soft}},
                                 "lab.toml");
    Daemon d(dir, "lab", ConfigText{config.text});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();

    const CommandResult to_demo = load_scene(dir, d.socket, demo);
    ASSERT_EQ(to_demo.exit_code, 0) << to_demo.err;
    EXPECT_NE(to_demo.out.find("the scene " + demo + "'s 1 environment: [[wall]] #1"),
              std::string::npos)
        << to_demo.out;
    const CommandResult stiffer = hapticctl(d.socket, "coupling 1600");
    EXPECT_EQ(stiffer.exit_code, 1) << "checked against the demo wall now in force";
    EXPECT_NE(stiffer.err.find("coupling refused: "), std::string::npos) << stiffer.err;
    EXPECT_NE(stiffer.err.find(demo), std::string::npos) << stiffer.err;

    ASSERT_EQ(load_scene(dir, d.socket, "soft-wall.toml").exit_code, 0);
    const CommandResult on_soft = hapticctl(d.socket, "coupling 1600");
    EXPECT_EQ(on_soft.exit_code, 0) << on_soft.err;
    const CommandResult refused = load_scene(dir, d.socket, demo);
    EXPECT_EQ(refused.exit_code, 1);
    EXPECT_NE(refused.err.find("scene_load refused: the stability check fails with the gains in "
                               "force: stability check (passive model, loop delay 1 ms)"),
              std::string::npos)
        << refused.err;
    const nlohmann::json kept = status_of(d.socket);
    EXPECT_EQ(kept["scene"]["name"], "soft-wall");
    EXPECT_EQ(kept["coupling"]["stiffness"], 1600.0);
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

}  // namespace
}  // namespace hapticd::testing
