// hapticd's run, in process and in lockstep: how it starts, what it refuses, how it ends.
// (tests/hil drives the real binary; these cover the glue's paths one by one.)
#include "hapticd/daemon/run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hapticd/tune/telemetry_log.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"

namespace hapticd::daemon {
namespace {

namespace fs = std::filesystem;

struct Outcome {
    int exit_code = -1;
    std::string out;
    std::string log;
    nlohmann::json summary() const { return nlohmann::json::parse(out); }
};

class DaemonRun : public ::testing::Test {
  protected:
    std::string write(const std::string& name, const std::string& text) const {
        return dir_.write(name, text);
    }

    static Outcome run(RunOptions options, bool stop_now = false) {
        options.status_interval_s = 0.0;
        std::atomic<bool> stop{stop_now};
        std::ostringstream out, log;
        Outcome outcome;
        outcome.exit_code = run_daemon(options, stop, out, log);
        outcome.out = out.str();
        outcome.log = log.str();
        return outcome;
    }

    /// A lockstep pen display pressing into the demo wall, with `extra` appended.
    std::string config(const std::string& coupling, const std::string& extra = "") const {
        write("wall.toml",
              "[scene]\nname = \"wall\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\nstiffness = 2e4\n");
        return write("lab.toml", R"(
[device]
plugin = "sim"
axes = 1
[device.model]
mass = 0.1
damping = 2.0
[device.sim]
mass = 0.1
damping = 2.0
clock = "lockstep"
initial_position = -0.005
[device.sim.human]
model = "stiff-grasp"
hand_mass = 0.3
hand_stiffness = 500.0
hand_damping = 5.0
push = { to = 0.005, start = 0.5, ramp = 0.5, hold = 5.0 }
[scene]
file = "wall.toml"
)" + coupling + "\n" + extra);
    }

    hapticd::testing::ScratchDir dir_;
};

constexpr const char* kEncoderGains = "[coupling]\nstiffness = 3600\ndamping = 0\n";

TEST_F(DaemonRun, LockstepRunOfTheEmbeddedDefaultGivesTheSummary) {
    RunOptions options;
    options.lockstep = true;
    options.duration_s = 2.5;
    options.summary_path = "-";
    const Outcome outcome = run(options);
    ASSERT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["ticks"], 2500);
    EXPECT_EQ(s["rate_hz"], 1000.0);
    EXPECT_EQ(s["overruns"], 0);
    EXPECT_EQ(s["exit"], "duration");
    EXPECT_EQ(s["config"], "<embedded default>");
    EXPECT_EQ(s["device"], "sim");
    EXPECT_EQ(s["scene"]["name"], "demo-wall");
    EXPECT_TRUE(s["lockstep"].get<bool>());
    EXPECT_TRUE(s["faults"].empty());
    EXPECT_EQ(s["realtime"]["mode"], "off");  // virtual time has no deadlines
    EXPECT_EQ(s["stability_check"]["model"], "passive");
    EXPECT_TRUE(s["stability_check"]["unconditionally_stable"].get<bool>());
    // The verdict names the class it rests on.
    EXPECT_NE(outcome.log.find("(passive model, loop delay 0 ms): unconditionally stable"),
              std::string::npos)
        << outcome.log;
    EXPECT_NE(outcome.log.find("holds for every passive operator and every passive environment"),
              std::string::npos)
        << outcome.log;
    // The default's grasp pushes 5 mm past the wall from t = 1 s: the wall pushes back.
    EXPECT_GT(s["max_force_n"].get<double>(), 1.0);
    EXPECT_LT(s["max_force_n"].get<double>(), 20.0);
    for (const char* key : {"p50", "p99", "p999", "max"})
        EXPECT_TRUE(s["wake_latency_us"].contains(key));
    for (const char* key : {"p50", "p99", "max"})
        EXPECT_GT(s["tick_compute_us"][key].get<double>(), 0.0);
}

TEST_F(DaemonRun, RefusesGainsThatFailTheCheckNamingMarginAndFrequency) {
    // 16000 N/m is what the paper's model allows for this device (8b/T); the encoder model
    // allows 2b/T = 4000 N/m, so the default check refuses it.
    RunOptions options;
    options.config_path = config("[coupling]\nstiffness = 16000\n");
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput);
    EXPECT_NE(outcome.log.find("lab.toml: refusing to arm: [coupling] stiffness = 16000 N/m"),
              std::string::npos)
        << outcome.log;
    EXPECT_NE(outcome.log.find("fail the passive model"), std::string::npos) << outcome.log;
    EXPECT_NE(outcome.log.find("worst margin -"), std::string::npos) << outcome.log;
    EXPECT_NE(outcome.log.find(" Hz"), std::string::npos) << outcome.log;
    EXPECT_NE(outcome.log.find("haptic-tune size --mass 0.1 --damping 2 --rate 1000"),
              std::string::npos)
        << outcome.log;
    EXPECT_TRUE(outcome.out.empty());
}

TEST_F(DaemonRun, TheCheckSeesTheVelocityFilter) {
    // k_c = 3600 N/m, b_c = 0.5 N s/m: the passive bound is k_c T/2 + b_c <= b unfiltered
    // (3000 N/m), k_c T/2 + b_c (1 - a)/(1 + a) <= b on a 100 Hz filter (3695.8 N/m).
    RunOptions options;
    options.config_path = config("[coupling]\nstiffness = 3600\ndamping = 0.5\n");
    Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput) << outcome.log;
    EXPECT_NE(outcome.log.find("fail the passive model"), std::string::npos) << outcome.log;

    options.config_path =
        config("[coupling]\nstiffness = 3600\ndamping = 0.5\nvelocity_filter = 100\n");
    options.duration_s = 0.5;
    options.lockstep = true;
    outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    EXPECT_NE(outcome.log.find("(passive model, loop delay 0 ms, velocity filter 100 Hz): "
                               "unconditionally stable, worst margin 0.0"),
              std::string::npos)
        << outcome.log;

    options.config_path =
        config("[coupling]\nstiffness = 3800\ndamping = 0.5\nvelocity_filter = 100\n");
    outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput) << outcome.log;
    EXPECT_NE(outcome.log.find("damping = 0.5 N s/m, velocity_filter = 100 Hz fail the passive "
                               "model"),
              std::string::npos)
        << outcome.log;
    EXPECT_NE(outcome.log.find("--rate 1000 --velocity-filter 100"), std::string::npos)
        << outcome.log;
}

TEST_F(DaemonRun, ThePaperModelCheckLetsThePaperGainsRun) {
    RunOptions options;
    options.config_path = config("[coupling]\nstiffness = 16000\ncheck = \"paper\"\n");
    options.duration_s = 0.1;
    options.lockstep = true;
    EXPECT_EQ(run(options).exit_code, kExitOk);
}

TEST_F(DaemonRun, LogIsCompleteInLockstep) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    options.duration_s = 3.0;
    options.summary_path = "-";
    options.log_path = dir_.file("run.csv");
    const Outcome outcome = run(options);
    ASSERT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["ticks"], 3000);
    EXPECT_EQ(s["telemetry_records"], 3000);
    EXPECT_EQ(s["telemetry_dropped"], 0);
    // Through the product's reader: every row has the header's fields, each a finite number.
    const hapticd::testing::TelemetryLog csv = hapticd::testing::read_telemetry(*options.log_path);
    const std::vector<std::string> first(
        csv.columns().begin(),
        csv.columns().begin() + std::min<std::size_t>(csv.columns().size(), 6));
    EXPECT_EQ(first,
              (std::vector<std::string>{"tick", "t_s", "unix_time_s", "x0_m", "v0_mps", "xe0_m"}));
    EXPECT_GT(csv.columns().size(), 6u);  // the status columns follow
    const std::vector<double>& tick = csv.column("tick");
    for (std::size_t row = 0; row < tick.size(); ++row) {
        EXPECT_EQ(tick[row], static_cast<double>(row));
    }
    EXPECT_EQ(csv.rows(), 3000u);
}

TEST_F(DaemonRun, WithoutReconnectADisconnectEndsTheRunOnAFaultAtZeroForce) {
    RunOptions options;
    options.config_path = config(
        kEncoderGains, "[safety]\nreconnect = false\n[device.sim.faults]\ndisconnect_at = 1.5\n");
    options.duration_s = 5.0;
    options.summary_path = "-";
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitFault);
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["exit"], "fault");
    EXPECT_EQ(s["faults"], nlohmann::json::array({"device_lost"}));
    EXPECT_NEAR(s["ticks"].get<double>(), 1500.0, 2.0);
    EXPECT_NE(outcome.log.find("stopped on a fault"), std::string::npos) << outcome.log;
}

// The sim's disconnect never comes back: with [safety] reconnect (the default) the loop
// keeps ticking at zero force, waiting, and ends the run reconnect_timeout after the fault.
TEST_F(DaemonRun, ADeviceThatDoesNotComeBackEndsTheRunAfterTheReconnectTimeout) {
    RunOptions options;
    options.config_path = config(kEncoderGains,
                                 "[safety]\nreconnect_timeout = 0.6\n"
                                 "[device.sim.faults]\ndisconnect_at = 1.5\n");
    options.duration_s = 5.0;
    options.summary_path = "-";
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitFault) << outcome.log;
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["exit"], "fault");
    EXPECT_EQ(s["faults"], nlohmann::json::array({"device_lost"}));
    EXPECT_EQ(s["link_recoveries"], 0);
    EXPECT_EQ(s["ticks"], 1500 + 600);  // the fault's tick at 1.5 s, and 0.6 s of waiting
    EXPECT_NE(outcome.log.find("fault device_lost, force zeroed; waiting for the device to come "
                               "back (at most 0.6 s, [safety] reconnect_timeout)"),
              std::string::npos)
        << outcome.log;
    EXPECT_NE(outcome.log.find("the device did not come back within [safety] reconnect_timeout "
                               "= 0.6 s"),
              std::string::npos)
        << outcome.log;
}

TEST_F(DaemonRun, ARunThatEndsWhileTheDeviceIsGoneIsAFault) {
    RunOptions options;
    options.config_path = config(kEncoderGains, "[device.sim.faults]\ndisconnect_at = 1.5\n");
    options.duration_s = 1.8;  // ends 0.3 s into the default 5 s reconnect_timeout
    options.summary_path = "-";
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitFault) << outcome.log;
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["exit"], "fault");
    EXPECT_EQ(s["faults"], nlohmann::json::array({"device_lost"}));
    EXPECT_EQ(s["ticks"], 1800);
    EXPECT_NE(outcome.log.find("the run ended with the link down (device_lost)"), std::string::npos)
        << outcome.log;
}

// Dropped replies (corrupted or missing frames) latch read_timeout; the device answers again
// and, 0.5 s later, the latch clears by itself: the run goes on to its end with exit 0.
TEST_F(DaemonRun, ALinkFaultRecoversWithoutARestart) {
    RunOptions options;
    options.config_path =
        config(kEncoderGains, "[device.sim.faults]\ndrop_at = [1.0, 1.001, 1.002, 1.003]\n");
    options.duration_s = 3.0;
    options.summary_path = "-";
    options.log_path = dir_.file("run.csv");
    const Outcome outcome = run(options);
    ASSERT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["exit"], "duration");
    EXPECT_EQ(s["ticks"], 3000);
    EXPECT_EQ(s["faults"], nlohmann::json::array({"read_timeout"}));
    EXPECT_EQ(s["link_recoveries"], 1);
    EXPECT_GT(s["max_force_n"].get<double>(), 1.0);  // pressing into the wall again after it
}

TEST_F(DaemonRun, AStopRequestEndsTheRunCleanly) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    options.summary_path = "-";
    const Outcome outcome = run(options, /*stop_now=*/true);
    EXPECT_EQ(outcome.exit_code, kExitOk);
    EXPECT_EQ(outcome.summary()["exit"], "stopped");
    EXPECT_EQ(outcome.summary()["ticks"], 0);
}

TEST_F(DaemonRun, SummaryGoesToAFile) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    options.duration_s = 0.2;
    options.summary_path = dir_.file("summary.json");
    ASSERT_EQ(run(options).exit_code, kExitOk);
    std::ifstream in(*options.summary_path);
    EXPECT_EQ(nlohmann::json::parse(in)["ticks"], 200);
}

TEST_F(DaemonRun, TheSummarySaysWhatRanWhenWhereAndFromWhichFile) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    options.lockstep = true;
    options.duration_s = 0.1;
    options.summary_path = "-";
    const auto before = std::chrono::system_clock::now();
    const Outcome outcome = run(options);
    ASSERT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    const nlohmann::json s = outcome.summary();
    EXPECT_EQ(s["version"], HAPTICD_TEST_VERSION);
    EXPECT_EQ(s["config_path"], fs::absolute(*options.config_path).lexically_normal().string());
    std::array<char, 256> host{};
    ASSERT_EQ(::gethostname(host.data(), host.size() - 1), 0);
    EXPECT_EQ(s["host"], host.data());
    // ISO 8601 in UTC, to the millisecond, within the run.
    const std::string started_at = s["started_at"];
    ASSERT_EQ(started_at.size(), 24u) << started_at;
    std::tm utc{};
    ASSERT_NE(::strptime(started_at.c_str(), "%Y-%m-%dT%H:%M:%S", &utc), nullptr) << started_at;
    EXPECT_EQ(started_at.substr(19), started_at.substr(19, 4) + "Z");
    const auto started = std::chrono::system_clock::from_time_t(::timegm(&utc));
    EXPECT_LE(started, std::chrono::system_clock::now());
    EXPECT_GE(started, std::chrono::floor<std::chrono::seconds>(before));

    RunOptions embedded;
    embedded.lockstep = true;
    embedded.duration_s = 0.01;
    embedded.summary_path = "-";
    const Outcome default_run = run(embedded);
    ASSERT_EQ(default_run.exit_code, kExitOk) << default_run.log;
    EXPECT_TRUE(default_run.summary()["config_path"].is_null());
    EXPECT_EQ(default_run.summary()["name"], "");  // [servo] name unset
}

// [servo] name labels the instance: in the summary and on the journal's start line.
TEST_F(DaemonRun, TheServoNameLabelsTheSummaryAndTheStartLine) {
    RunOptions options;
    options.config_path = config(kEncoderGains, "[servo]\nname = \"left arm\"\n");
    options.lockstep = true;
    options.duration_s = 0.05;
    options.summary_path = "-";
    options.log_path = dir_.file("named.csv");
    const Outcome outcome = run(options);
    ASSERT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    EXPECT_EQ(outcome.summary()["name"], "left arm");
    EXPECT_NE(outcome.log.find("hapticd: left arm: sim device"), std::string::npos) << outcome.log;
    // And the log: its preamble names the instance, and haptic-tune's reader reads past it.
    const tune::TelemetryLog log = tune::read_telemetry_log(*options.log_path);
    ASSERT_NE(log.preamble_value("name"), nullptr);
    EXPECT_EQ(*log.preamble_value("name"), "left arm");
    EXPECT_EQ(log.rows(), 50u);
    EXPECT_EQ(log.line(0),
              log.preamble.size() + 3);  // after the preamble, its title and the header
}

TEST_F(DaemonRun, EachStartWritesFilesOfItsOwnWhereThePathsSayStart) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    options.lockstep = true;
    options.duration_s = 0.05;
    options.summary_path = dir_.file("summary-{start}.json");
    options.log_path = dir_.file("telemetry-{start}.csv");
    ASSERT_EQ(run(options).exit_code, kExitOk);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_EQ(run(options).exit_code, kExitOk);
    std::vector<std::string> summaries, logs;
    for (const auto& entry : fs::directory_iterator(dir_.path())) {
        const std::string name = entry.path().filename().string();
        if (name.starts_with("summary-")) summaries.push_back(name);
        if (name.starts_with("telemetry-")) logs.push_back(name);
    }
    ASSERT_EQ(summaries.size(), 2u);
    ASSERT_EQ(logs.size(), 2u);
    for (const std::string& name : summaries) {
        std::ifstream in(dir_.path() / name);
        const nlohmann::json s = nlohmann::json::parse(in);
        EXPECT_EQ(s["ticks"], 50);
        // summary-20261203T124100.123Z.json of a run that started at 2026-12-03T12:41:00.123Z
        std::string stamp = s["started_at"];
        std::erase(stamp, '-');
        std::erase(stamp, ':');
        EXPECT_EQ(name, "summary-" + stamp + ".json");
        EXPECT_NE(std::find(logs.begin(), logs.end(), "telemetry-" + stamp + ".csv"), logs.end())
            << name;
    }
}

TEST_F(DaemonRun, TheRunsFiguresGoToTheLogAtTheirInterval) {
    RunOptions options;  // the embedded default: the sim on the wall clock
    options.duration_s = 0.45;
    options.figures_interval_s = 0.1;
    const Outcome outcome = run(options);
    ASSERT_EQ(outcome.exit_code, kExitOk) << outcome.log;
    std::istringstream lines(outcome.log);
    std::vector<std::string> figures;
    for (std::string line; std::getline(lines, line);) {
        if (line.find(" Hz over the last ") != std::string::npos) figures.push_back(line);
    }
    // Four on a machine that keeps time; a stalled one gives fewer, never more.
    ASSERT_GE(figures.size(), 1u) << outcome.log;
    ASSERT_LE(figures.size(), 5u) << outcome.log;
    double previous_t_s = -1.0;
    for (const std::string& line : figures) {
        EXPECT_TRUE(line.starts_with("<6>hapticd: t ")) << line;  // info, for the journal
        EXPECT_NE(line.find(", faults none"), std::string::npos) << line;
        // Each line covers the time since the last, at least the interval: never two of
        // the same moment (a late look once wrote one line per interval it had missed).
        const double t_s = std::stod(line.substr(std::string("<6>hapticd: t ").size()));
        EXPECT_GT(t_s, previous_t_s) << outcome.log;
        previous_t_s = t_s;
        const std::size_t over = line.find(" Hz over the last ") + 18;
        EXPECT_GE(std::stod(line.substr(over)), 0.1) << line;
    }
}

struct BadStart {
    std::string what;
    std::string coupling;
    std::string extra;
    std::string message;
};

class DaemonRunRefuses : public DaemonRun, public ::testing::WithParamInterface<BadStart> {};

TEST_P(DaemonRunRefuses, WithExitTwoAndAMessageNamingTheProblem) {
    RunOptions options;
    options.config_path = config(GetParam().coupling, GetParam().extra);
    options.duration_s = 0.1;
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput) << outcome.log;
    EXPECT_NE(outcome.log.find(GetParam().message), std::string::npos) << outcome.log;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, DaemonRunRefuses,
    ::testing::Values(
        BadStart{"unknown key", kEncoderGains, "[safety]\nmax_torque = 3\n",
                 "[safety] max_torque = 3 is not a known key"},
        BadStart{"sim table", kEncoderGains, "[device.sim.faults]\nseed = -1\n",
                 "[device.sim.faults] seed = -1 is out of range"},
        BadStart{"no gains", "[coupling]\ncheck = \"encoder\"\n", "",
                 "[coupling] stiffness and damping are both 0"},
        BadStart{"velocity filter above Nyquist",
                 "[coupling]\nstiffness = 3600\ndamping = 0.5\nvelocity_filter = 600\n", "",
                 "lab.toml:24: [coupling] velocity_filter = 600 is out of range: "
                 "allowed 0 (no filter) or >= 1 and < 500"}),
    [](const ::testing::TestParamInfo<BadStart>& param_info) {
        std::string name = param_info.param.what;
        for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
        return name;
    });

TEST_F(DaemonRun, NoCouplingIsRefusedForAnAdmittanceScene) {
    write("sphere.toml", "[scene]\nname = \"ball\"\naxes = 1\n[[proxy_plane]]\nnormal = [-1.0]\n");
    std::string text = config("[coupling]\nenabled = false\ncheck = \"off\"\n");
    std::ifstream in(text);
    std::stringstream body;
    body << in.rdbuf();
    std::string replaced = body.str();
    replaced.replace(replaced.find("wall.toml"), 9, "sphere.toml");
    RunOptions options;
    options.config_path = write("lab.toml", replaced);
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput);
    EXPECT_NE(outcome.log.find("is an admittance (constraint) scene, which needs the coupling"),
              std::string::npos)
        << outcome.log;
}

TEST_F(DaemonRun, AnUnknownPluginIsNamed) {
    std::string text = config(kEncoderGains);
    std::ifstream in(text);
    std::stringstream body;
    body << in.rdbuf();
    std::string replaced = body.str();
    replaced.replace(replaced.find("plugin = \"sim\""), 14, "plugin = \"nosuchdevice\"");
    replaced.replace(replaced.find("[device.sim]"), 12, "[device.nosuchdevice]");
    replaced.replace(replaced.find("[device.sim.human]"), 18, "[device.nosuchdevice.human]");
    RunOptions options;
    options.config_path = write("lab.toml", replaced);
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput);
    EXPECT_NE(outcome.log.find("[device] plugin = \"nosuchdevice\""), std::string::npos)
        << outcome.log;
}

TEST_F(DaemonRun, ABadSceneIsNamed) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    write("wall.toml",
          "[scene]\nname = \"wall\"\naxes = 1\n[[wall]]\nnormal = [-1.0]\nstiffness = -5\n");
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput);
    EXPECT_NE(outcome.log.find("wall.toml"), std::string::npos) << outcome.log;
    EXPECT_NE(outcome.log.find("stiffness = -5"), std::string::npos) << outcome.log;
}

// docs/architecture.md §7.9 (a scene the coupling cannot render): a detent with period =
// 1e-300 was once accepted, and the series solve (17) then failed on every tick without a
// word. Its stiffness between notches, -2π peak_force/period, must stay above -k_c.
TEST_F(DaemonRun, ADetentTheCouplingCannotRenderIsRefusedBeforeTheRun) {
    RunOptions options;
    options.config_path = config(kEncoderGains);
    const std::string detent =
        "[scene]\nname = \"notches\"\naxes = 1\n[[detent]]\naxis = [1.0]\n"
        "peak_force = 1.0\nperiod = ";
    write("wall.toml", detent + "1e-300\n");
    const Outcome refused = run(options);
    EXPECT_EQ(refused.exit_code, kExitBadInput);
    EXPECT_NE(refused.log.find("wall.toml: [[detent]] #1 has a stiffness down to -6.28319e+300 "
                               "N/m between its notches (-2π peak_force/period), out of range "
                               "for this coupling: allowed > -k_c = -3600 N/m"),
              std::string::npos)
        << refused.log;
    EXPECT_TRUE(refused.out.empty());  // no run, no summary
    // 2π x 1 N / 2 mm = 3142 N/m < 3600 N/m: rendered.
    write("wall.toml", detent + "0.002\n");
    options.duration_s = 0.2;
    options.lockstep = true;
    options.summary_path = "-";
    const Outcome ran = run(options);
    EXPECT_EQ(ran.exit_code, 0) << ran.log;
    EXPECT_EQ(ran.summary().at("solver_not_converged"), 0);
}

TEST_F(DaemonRun, AMissingConfigFileIsNamed) {
    RunOptions options;
    options.config_path = dir_.file("absent.toml");
    const Outcome outcome = run(options);
    EXPECT_EQ(outcome.exit_code, kExitBadInput);
    EXPECT_NE(outcome.log.find("absent.toml: cannot read the config file"), std::string::npos)
        << outcome.log;
}

}  // namespace
}  // namespace hapticd::daemon
