// hapticctl identify against a running hapticd (docs/control.md, "identify"): the excitation of
// `hapticd --identify` played open loop on the disarmed daemon, recorded to a log beside its
// other files, without stopping it. Judged by value: the log's open-loop ticks command the
// planned signal to the last bit, haptic-tune identify finds the sim's mass and damping in
// it, and the daemon renders its scene again once armed. Plus the refusals, and a disarm
// that ends the excitation early.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "config_editor.hpp"
#include "control_daemon.hpp"
#include "hapticd/daemon/config.hpp"
#include "hapticd/daemon/servo_settings.hpp"
#include "hapticd/env/excitation.hpp"
#include "hapticd/servo/telemetry.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"
#include "text_file.hpp"
#include "unix_client.hpp"

namespace hapticd::testing {
namespace {

using namespace std::chrono_literals;

// A short excitation: 2..40 Hz about the pen's corner b/(2 pi m) = 3.2 Hz, three 1 s periods
// and a quarter-second fade in and out (3.5 s once the handle is still).
constexpr const char* kShortIdentify =
    "[identify]\nband_low = 2.0\nband_high = 40.0\nperiod = 1.0\nperiods = 3\nfade = 0.25\n";

// The default config (the sim's pen display, m = 0.1 kg and b = 2 N s/m, and the demo wall)
// with room for the VM's stalls, nobody holding the handle (1 cm in front of the wall), and
// the short excitation.
std::string hands_off_config() {
    std::string config = config_with_room("");
    config.erase(config.find("[device.sim.human]"));
    return config + "[device.sim.human]\nmodel = \"hands-off\"\n" + kShortIdentify;
}

// The excitation the daemon plans for `config_toml` on the sim (20 N).
env::ExcitationEnvironment planned_excitation(const std::string& config_toml) {
    const daemon::Config config = daemon::parse_config(config_toml, "lab.toml", "");
    device::DeviceInfo info;
    info.axes = 1;
    info.counts_per_meter = 1e5;
    info.force_limit_n = 20.0;
    info.name = "sim";
    return env::ExcitationEnvironment(daemon::make_identify_plan(config, info).excitation);
}

bool has_flag(double flags, std::uint32_t flag) {
    return (static_cast<std::uint32_t>(flags) & flag) != 0u;
}

// The log's open-loop ticks that had a sample over a known interval, in order: the ones the
// excitation played a sample on.
struct PlayedTicks {
    std::vector<double> force_n;
    std::size_t open_loop_rows = 0;
};

PlayedTicks played_ticks(const TelemetryLog& log) {
    const auto& flags = log.column("tick_flags");
    const auto& f = log.column("f0_n");
    PlayedTicks played;
    for (std::size_t row = 0; row < log.rows(); ++row) {
        if (!has_flag(flags[row], servo::kFlagOpenLoop)) continue;
        ++played.open_loop_rows;
        if (has_flag(flags[row], servo::kFlagNoSample | servo::kFlagIntervalUnknown)) continue;
        played.force_n.push_back(f[row]);
    }
    return played;
}

// The rows of `played` bit for bit against the planned signal, aligned at its first force:
// the number that differ, or the played count when nothing was ever pushed.
std::size_t mismatches_with_plan(const std::vector<double>& played,
                                 const env::ExcitationEnvironment& e) {
    std::int64_t first_planned = 0;
    while (e.scheduled_force_n(first_planned).x == 0.0) ++first_planned;
    std::size_t first_played = 0;
    while (first_played < played.size() && played[first_played] == 0.0) ++first_played;
    if (first_played == played.size()) return played.size();
    const std::int64_t start = static_cast<std::int64_t>(first_played) - first_planned;
    std::size_t mismatches = 0;
    for (std::size_t k = 0; k < played.size(); ++k) {
        mismatches += played[k] != e.scheduled_force_n(static_cast<std::int64_t>(k) - start).x;
    }
    return mismatches;
}

#define EXPECT_CONTAINS(text, part) \
    EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

TEST(HilIdentifySocket, TheExcitationPlaysOnTheDisarmedDaemonAndIdentifiesThePen) {
    const ScratchDir dir;
    const std::string config = hands_off_config();
    Daemon d(dir, "lab", ConfigText{config});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    const nlohmann::json first = status_when(d.socket, armed_state);
    EXPECT_TRUE(first["identify"].is_null()) << first.dump();

    // Only on a disarmed daemon: nobody is to be holding the handle.
    const CommandResult armed = hapticctl(d.socket, "identify");
    EXPECT_EQ(armed.exit_code, 1);
    EXPECT_CONTAINS(armed.err, "identify refused: identify starts on a disarmed daemon");
    EXPECT_CONTAINS(armed.err, "hapticctl disarm");
    ASSERT_EQ(hapticctl(d.socket, "disarm").exit_code, 0);
    status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "disabled"; });

    const auto started = std::chrono::steady_clock::now();
    const CommandResult played = hapticctl(d.socket, "identify");
    const double took_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    ASSERT_EQ(played.exit_code, 0) << played.out << played.err;
    const env::ExcitationEnvironment e = planned_excitation(config);
    const double excitation_s = static_cast<double>(e.samples()) / 1000.0;
    EXPECT_CONTAINS(played.out, "the log is " + dir.file("identify-"));
    EXPECT_CONTAINS(played.out, "identify: the excitation ran to its end: 3.5 s from ");
    EXPECT_GT(took_s, excitation_s) << "hapticctl waits for the end";

    const nlohmann::json after = status_of(d.socket);
    const nlohmann::json& run = after["identify"];
    ASSERT_TRUE(run.is_object()) << after.dump();
    EXPECT_EQ(run["active"], false);
    EXPECT_EQ(run["complete"], true);
    EXPECT_EQ(run["phase"], "finished");
    EXPECT_DOUBLE_EQ(run["played_s"].get<double>(), excitation_s);
    EXPECT_TRUE(after["recording"].is_null()) << "the log ended with the excitation";
    EXPECT_EQ(after["state"], "disabled") << "the excitation leaves the daemon disarmed";
    const std::string log_path = run["path"].get<std::string>();
    EXPECT_EQ(std::filesystem::path(log_path).parent_path(), dir.path());

    // The log: every open-loop tick with a sample commands the planned signal exactly, and
    // the ticks the excitation played on are its whole length and the still wait before it.
    const TelemetryLog log = read_telemetry(log_path);
    const PlayedTicks ticks = played_ticks(log);
    EXPECT_GE(ticks.force_n.size(), static_cast<std::size_t>(e.samples()));
    EXPECT_EQ(mismatches_with_plan(ticks.force_n, e), 0u);
    const auto& flags = log.column("tick_flags");
    EXPECT_FALSE(has_flag(flags.back(), servo::kFlagOpenLoop)) << "the log ends let go";
    EXPECT_EQ(log.column("f0_n").back(), 0.0);

    // What it is for: haptic-tune identify reads the sim's pen display out of it.
    const CommandResult identified = run_command(shell_quote(HAPTIC_TUNE_BIN) + " identify " +
                                                 shell_quote(log_path) + " --json");
    ASSERT_EQ(identified.exit_code, 0) << identified.err;
    const nlohmann::json model = nlohmann::json::parse(identified.out);
    std::cout << "[hil] identify over the socket: " << log.rows() << " rows, "
              << ticks.open_loop_rows << " open loop (" << ticks.force_n.size()
              << " with a sample), hapticctl waited " << took_s
              << " s; identified m = " << model["mass"] << " kg, b = " << model["damping"]
              << " N s/m\n";
    EXPECT_NEAR(model["mass"].get<double>(), 0.1, 0.005);
    EXPECT_NEAR(model["damping"].get<double>(), 2.0, 0.1);

    // Armed again, the daemon renders its scene through the soft start.
    ASSERT_EQ(hapticctl(d.socket, "arm").exit_code, 0);
    const nlohmann::json rearmed =
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "running"; });
    EXPECT_EQ(rearmed["state"], "running") << rearmed.dump();
    EXPECT_EQ(rearmed["scene"]["name"], "demo-wall");
    EXPECT_EQ(rearmed["faults"].size(), 0u) << rearmed.dump();

    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    const std::string messages = d.process.messages();
    EXPECT_CONTAINS(messages, "control: identify from pid ");
    EXPECT_CONTAINS(messages, "playing the excitation open loop");
    EXPECT_CONTAINS(messages, "hapticd: identify: the excitation ran to its end");
    const nlohmann::json summary = nlohmann::json::parse(read_file(d.summary));
    ASSERT_EQ(summary["identify"].size(), 1u) << summary.dump(2);
    EXPECT_EQ(summary["identify"][0]["path"], log_path);
    EXPECT_EQ(summary["identify"][0]["complete"], true);
    ASSERT_EQ(summary["recordings"].size(), 1u);
    EXPECT_EQ(summary["recordings"][0]["records"], log.rows());
}

// A run of constraint scenes (the god-object's plane) plays the same excitation: the source
// takes the place of the admittance environment and the coupling as it does of a wall's.
TEST(HilIdentifySocket, AnAdmittanceRunPlaysTheSameExcitation) {
    const ScratchDir dir;
    const std::string plane = dir.write(
        "plane.toml",
        "[scene]\nname = \"plane\"\naxes = 1\n[[proxy_plane]]\nnormal = [-1.0]\noffset = 0.0\n");
    const std::string config =
        daemon::edit_config_text(hands_off_config(), {{"scene", "file", plane}}, "lab.toml").text;
    Daemon d(dir, "lab", ConfigText{config});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    EXPECT_EQ(status_when(d.socket, armed_state)["scene"]["name"], "plane");
    ASSERT_EQ(hapticctl(d.socket, "disarm").exit_code, 0);
    const CommandResult played = hapticctl(d.socket, "identify " + dir.file("plane-run.csv"));
    ASSERT_EQ(played.exit_code, 0) << played.out << played.err;
    const TelemetryLog log = read_telemetry(dir.file("plane-run.csv"));
    const PlayedTicks ticks = played_ticks(log);
    const env::ExcitationEnvironment e = planned_excitation(config);
    EXPECT_GE(ticks.force_n.size(), static_cast<std::size_t>(e.samples()));
    EXPECT_EQ(mismatches_with_plan(ticks.force_n, e), 0u);
    ASSERT_EQ(hapticctl(d.socket, "arm").exit_code, 0);
    const nlohmann::json rearmed =
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "running"; });
    EXPECT_EQ(rearmed["state"], "running") << rearmed.dump();
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

TEST(HilIdentifySocket, WhileItPlaysTheSceneAndTheRecordingAreItsAndADisarmOrAStopEndsIt) {
    const ScratchDir dir;
    const std::string config = hands_off_config();
    Daemon d(dir, "lab", ConfigText{config});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    ASSERT_EQ(hapticctl(d.socket, "disarm").exit_code, 0);
    status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "disabled"; });

    // Bad usage is exit 2, and says what is wrong.
    const struct {
        const char* arguments;
        const char* says;
    } bad_usage[] = {
        {"identify a.csv b.csv", "b.csv"},
        {"identify ''", "the path is empty"},
        {"identify --periods 2", "--periods"},
    };
    for (const auto& c : bad_usage) {
        SCOPED_TRACE(c.arguments);
        const CommandResult r = hapticctl(d.socket, c.arguments);
        EXPECT_EQ(r.exit_code, 2) << r.err;
        EXPECT_CONTAINS(r.err, c.says);
    }
    EXPECT_TRUE(status_of(d.socket)["identify"].is_null()) << "nothing was started";

    // The recording is the excitation's log, so one already running comes first.
    ASSERT_EQ(hapticctl(d.socket, "record start " + dir.file("take.csv")).exit_code, 0);
    const CommandResult recording = hapticctl(d.socket, "identify");
    EXPECT_EQ(recording.exit_code, 1);
    EXPECT_CONTAINS(recording.err, "identify refused: already recording to " +
                                       dir.file("take.csv") + " (record stop first)");
    ASSERT_EQ(hapticctl(d.socket, "record stop").exit_code, 0);

    // A log that exists is not overwritten; a relative one is the caller's directory's.
    dir.write("taken.csv", "keep me\n");
    const CommandResult taken =
        run_command("cd " + shell_quote(dir.path().string()) + " && " + shell_quote(HAPTICCTL_BIN) +
                    " --socket " + shell_quote(d.socket) + " identify taken.csv");
    EXPECT_EQ(taken.exit_code, 1);
    EXPECT_CONTAINS(taken.err, dir.file("taken.csv"));
    EXPECT_EQ(read_file(dir.file("taken.csv")), "keep me\n");
    EXPECT_TRUE(status_of(d.socket)["identify"].is_null()) << "nothing was started";

    const CommandResult started =
        run_command("cd " + shell_quote(dir.path().string()) + " && " + shell_quote(HAPTICCTL_BIN) +
                    " --socket " + shell_quote(d.socket) + " identify pen.csv --no-wait");
    ASSERT_EQ(started.exit_code, 0) << started.err;
    EXPECT_CONTAINS(started.out, "the log is " + dir.file("pen.csv"));
    const nlohmann::json playing = status_when(d.socket, [](const nlohmann::json& s) {
        return s["identify"].is_object() && s["identify"]["phase"] == "running";
    });
    ASSERT_EQ(playing["identify"]["phase"], "running") << playing.dump();
    EXPECT_EQ(playing["identify"]["active"], true);
    EXPECT_EQ(playing["recording"], dir.file("pen.csv"));
    EXPECT_EQ(playing["state"], "running");

    // The excitation has the handle, the recording and the scene until it ends.
    const CommandResult again = hapticctl(d.socket, "identify --no-wait");
    EXPECT_EQ(again.exit_code, 1);
    EXPECT_CONTAINS(again.err,
                    "an excitation is playing already (the log is " + dir.file("pen.csv"));
    dir.write("near-wall.toml",
              "[scene]\nname = \"near-wall\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\n"
              "offset = 0.015\nstiffness = 2000.0\n");
    const CommandResult scene = hapticctl(d.socket, "scene " + dir.file("near-wall.toml"));
    EXPECT_EQ(scene.exit_code, 1);
    EXPECT_CONTAINS(scene.err, "scene_load refused: identify is playing the excitation");
    const CommandResult coupling = hapticctl(d.socket, "coupling 3000");
    EXPECT_EQ(coupling.exit_code, 1);
    EXPECT_CONTAINS(coupling.err, "identify is playing the excitation");
    const CommandResult stop = hapticctl(d.socket, "record stop");
    EXPECT_EQ(stop.exit_code, 1);
    EXPECT_CONTAINS(stop.err, "the recording is identify's log");

    ASSERT_EQ(hapticctl(d.socket, "disarm").exit_code, 0);
    const nlohmann::json ended = status_when(d.socket, [](const nlohmann::json& s) {
        return s["identify"].is_object() && s["identify"]["active"] == false;
    });
    const nlohmann::json& run = ended["identify"];
    ASSERT_EQ(run["active"], false) << ended.dump();
    EXPECT_EQ(run["complete"], false);
    EXPECT_EQ(run["phase"], "interrupted");
    EXPECT_CONTAINS(run["outcome"].get<std::string>(), "WARNING: the run ended ");
    EXPECT_CONTAINS(run["outcome"].get<std::string>(),
                    ", stopped by a disarm; the log is " + dir.file("pen.csv"));
    EXPECT_LT(run["played_s"].get<double>(), run["excitation_s"].get<double>());
    EXPECT_TRUE(ended["recording"].is_null()) << ended.dump();

    // What was played is the plan's start, to the bit, and the log ends at zero force.
    const TelemetryLog log = read_telemetry(dir.file("pen.csv"));
    const PlayedTicks ticks = played_ticks(log);
    EXPECT_GT(ticks.force_n.size(), 0u);
    EXPECT_EQ(mismatches_with_plan(ticks.force_n, planned_excitation(config)), 0u);
    EXPECT_EQ(log.column("f0_n").back(), 0.0);

    // Afterwards the scene loads again, and a second excitation plays to a new default log.
    EXPECT_EQ(hapticctl(d.socket, "scene " + dir.file("near-wall.toml")).exit_code, 0);
    const CommandResult second = hapticctl(d.socket, "identify --no-wait");
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_CONTAINS(second.out, "the log is " + dir.file("identify-"));
    const nlohmann::json second_playing = status_when(d.socket, [](const nlohmann::json& s) {
        return s["identify"]["phase"] == "running" && s["identify"]["played_s"] > 0.1;
    });
    const std::string second_log = second_playing["identify"]["path"].get<std::string>();

    // A run stopped while it plays (SIGTERM) ends it cleanly: zero force, the log whole.
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    const std::string messages = d.process.messages();
    EXPECT_CONTAINS(messages, ", stopped by a disarm; the log is " + dir.file("pen.csv"));
    EXPECT_CONTAINS(messages, ", stopped by the end of the run; the log is " + second_log);
    // The summary lists every file recorded and every excitation, in order.
    const nlohmann::json summary = nlohmann::json::parse(read_file(d.summary));
    const nlohmann::json& recordings = summary["recordings"];
    ASSERT_EQ(recordings.size(), 3u) << summary.dump(2);
    EXPECT_EQ(recordings[0]["path"], dir.file("take.csv"));
    EXPECT_EQ(recordings[1]["path"], dir.file("pen.csv"));
    EXPECT_EQ(recordings[2]["path"], second_log);
    for (const nlohmann::json& file : recordings) {
        EXPECT_EQ(file["records"].get<std::size_t>(),
                  read_telemetry(file["path"].get<std::string>()).rows())
            << file.dump();
        EXPECT_EQ(file["dropped"], 0) << file.dump();
    }
    const nlohmann::json& runs = summary["identify"];
    ASSERT_EQ(runs.size(), 2u) << summary.dump(2);
    EXPECT_EQ(runs[0]["path"], dir.file("pen.csv"));
    EXPECT_EQ(runs[0]["complete"], false);
    EXPECT_CONTAINS(runs[0]["outcome"].get<std::string>(), "stopped by a disarm");
    EXPECT_EQ(runs[1]["path"], second_log);
    EXPECT_CONTAINS(runs[1]["outcome"].get<std::string>(), "stopped by the end of the run");
    const TelemetryLog stopped = read_telemetry(second_log);
    EXPECT_GT(played_ticks(stopped).force_n.size(), 100u);
    EXPECT_EQ(mismatches_with_plan(played_ticks(stopped).force_n, planned_excitation(config)), 0u);
}

// The busy check runs when a request's work runs, not when its line is read (issue 28: a
// record_stop read while another client's identify was still being set up ended identify's
// log at 0 records, and identify still said it ran to its end, complete).
TEST(HilIdentifySocket, ARequestQueuedBehindAnIdentifyIsCheckedWhenItRuns) {
    const ScratchDir dir;
    Daemon d(dir, "lab", ConfigText{hands_off_config()});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    ASSERT_EQ(hapticctl(d.socket, "disarm").exit_code, 0);
    UnixClient identify(d.socket);
    UnixClient other(d.socket);
    ASSERT_TRUE(identify.send(R"({"v":1,"id":1,"request":"identify","path":"pen.csv"})"
                              "\n"));
    ASSERT_TRUE(other.send(R"({"v":1,"id":2,"request":"record_stop"})"
                           "\n"
                           R"({"v":1,"id":3,"request":"coupling","stiffness":3000})"
                           "\n"));
    const auto started = identify.line();
    ASSERT_TRUE(started.has_value());
    EXPECT_EQ(nlohmann::json::parse(*started)["ok"], true) << *started;
    for (const char* says : {"record_stop refused: the recording is identify's log",
                             "coupling refused: identify is playing the excitation"}) {
        const auto reply = other.line();
        ASSERT_TRUE(reply.has_value());
        EXPECT_CONTAINS(*reply, says);
    }
    const nlohmann::json ended = status_when(
        d.socket,
        [](const nlohmann::json& s) {
            return s["identify"].is_object() && s["identify"]["active"] == false;
        },
        30s);
    EXPECT_EQ(ended["identify"]["complete"], true) << ended.dump();
    EXPECT_GT(read_telemetry(dir.file("pen.csv")).rows(), 3000u);  // the whole 3.5 s, and more
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

// A reset ends an excitation, and its outcome says so (issue 28: with no fault latched it
// ended it silently: "stopped by a disarm").
TEST(HilIdentifySocket, AResetThatEndsTheExcitationIsNamedInItsOutcome) {
    const ScratchDir dir;
    Daemon d(dir, "lab", ConfigText{hands_off_config()});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    ASSERT_EQ(hapticctl(d.socket, "disarm").exit_code, 0);
    ASSERT_EQ(hapticctl(d.socket, "identify pen.csv --no-wait").exit_code, 0);
    status_when(d.socket, [](const nlohmann::json& s) {
        return s["identify"].is_object() && s["identify"]["phase"] == "running";
    });
    ASSERT_EQ(hapticctl(d.socket, "reset").exit_code, 0);
    const nlohmann::json ended = status_when(d.socket, [](const nlohmann::json& s) {
        return s["identify"].is_object() && s["identify"]["active"] == false;
    });
    ASSERT_EQ(ended["identify"]["active"], false) << ended.dump();
    EXPECT_EQ(ended["identify"]["complete"], false);
    EXPECT_CONTAINS(ended["identify"]["outcome"].get<std::string>(), "stopped by a reset");
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

// A full disk under the outputs directory (a 64 KiB tmpfs as LOGS_DIRECTORY): a recording
// and an identify log that are not whole say so in the reply, the outcome, the summary and
// the exit status (3), as --log does (issue 28: both were reported whole, exit 0).
TEST(HilIdentifySocket, ALogOnAFullDiskIsIncompleteInTheReplyTheOutcomeTheSummaryAndTheExit) {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root, to mount a small tmpfs";
    const ScratchDir dir;
    const std::string logs = dir.file("logs");
    std::filesystem::create_directory(logs);
    if (::mount("tmpfs", logs.c_str(), "tmpfs", 0, "size=64k") != 0) {
        GTEST_SKIP() << "cannot mount a tmpfs here";
    }
    struct Unmount {
        std::string path;
        ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
    } unmount{logs};
    const std::string socket = dir.file("lab.sock");
    const std::string summary = dir.file("summary.json");
    BackgroundDaemon daemon(
        "/usr/bin/env",
        {"LOGS_DIRECTORY=" + logs, HAPTICD_BIN, "--no-status", "--config",
         dir.write("lab.toml", hands_off_config()), "--socket", socket, "--summary", summary},
        dir.file("lab.err"));
    ASSERT_TRUE(daemon.wait_for_socket(socket)) << daemon.messages();

    EXPECT_TRUE(status_of(socket)["recording_whole"].is_null());
    ASSERT_EQ(hapticctl(socket, "record start take.csv").exit_code, 0);
    // 1500 rows, past 64 KiB: status says so while it records.
    const nlohmann::json failing =
        status_when(socket, [](const nlohmann::json& s) { return s["recording_whole"] == false; });
    EXPECT_EQ(failing["recording_whole"], false) << failing.dump();
    std::this_thread::sleep_for(500ms);
    const CommandResult stopped = hapticctl(socket, "record stop");
    EXPECT_EQ(stopped.exit_code, 1);
    EXPECT_CONTAINS(stopped.err,
                    "the recording is INCOMPLETE: writing telemetry failed: No "
                    "space left on device; the file holds the first ");

    ASSERT_EQ(hapticctl(socket, "disarm").exit_code, 0);
    const CommandResult identified = hapticctl(socket, "identify pen.csv");
    EXPECT_EQ(identified.exit_code, 1);
    EXPECT_CONTAINS(identified.err,
                    "the log is INCOMPLETE: writing telemetry failed: No space "
                    "left on device");

    EXPECT_EQ(daemon.stop(), 3) << daemon.messages();
    const nlohmann::json s = nlohmann::json::parse(read_file(summary));
    ASSERT_EQ(s["recordings"].size(), 2u) << s.dump(2);
    for (const nlohmann::json& file : s["recordings"]) {
        EXPECT_EQ(file["complete"], false) << file.dump();
        EXPECT_CONTAINS(file["failure"].get<std::string>(), "No space left on device");
    }
    EXPECT_EQ(s["identify"][0]["complete"], false);
    EXPECT_CONTAINS(daemon.messages(), "recordings of the control socket are incomplete");
}

}  // namespace
}  // namespace hapticd::testing
