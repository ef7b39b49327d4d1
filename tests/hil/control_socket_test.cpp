// The control socket and hapticctl end to end (docs/control.md, hapticctl(1)): real hapticd
// processes on the simulated device in real time, driven by the real hapticctl, and by raw
// clients that send what hapticctl never would. The servo loop must not notice any of it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "background_daemon.hpp"
#include "control_daemon.hpp"
#include "default_config.hpp"
#include "hapticd_run.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "telemetry_csv.hpp"
#include "text_file.hpp"
#include "unix_client.hpp"

namespace hapticd::testing {
namespace {

using namespace std::chrono_literals;

TEST(HilControlSocket, StatusDisarmArmAFaultItsRefusalAndResetThroughHapticctl) {
    const ScratchDir dir;
    // An encoder jump (0.2 m) at 2.5 s: a fault that needs an operator.
    Daemon d(
        dir, "lab",
        ConfigText{config_with_room("[device.sim.faults]\njump_at = 2.5\njump_counts = 20000\n",
                                    "name = \"rig 2\"\n")});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();

    const nlohmann::json first = status_of(d.socket);
    ASSERT_FALSE(first.is_null());
    EXPECT_EQ(first["name"], "rig 2");                // [servo] name
    EXPECT_TRUE(armed_state(first)) << first.dump();  // the daemon starts armed
    EXPECT_EQ(first["rate_hz"], 1000.0);
    EXPECT_EQ(first["axes"], 1);
    EXPECT_EQ(first["x_m"].size(), 1u);
    EXPECT_NE(first["device"].get<std::string>().find("sim"), std::string::npos);
    EXPECT_TRUE(first["config_path"].get<std::string>().ends_with("/lab.toml"));

    // The watcher's rate over a whole second, once the servo has run one.
    const nlohmann::json ticking =
        status_when(d.socket, [](const nlohmann::json& s) { return s["t_s"] >= 1.2; });
    EXPECT_NEAR(ticking["measured_rate_hz"].get<double>(), 1000.0, 60.0) << ticking.dump();
    // The percentiles of the first second: a real wake-up takes microseconds, a tick less
    // than a period.
    EXPECT_GT(ticking["wake_latency_us"]["p50"].get<double>(), 0.0) << ticking.dump();
    EXPECT_GE(ticking["wake_latency_us"]["max"], ticking["wake_latency_us"]["p99"]);
    EXPECT_GT(ticking["tick_compute_us"]["p50"].get<double>(), 0.0);
    EXPECT_LT(ticking["tick_compute_us"]["p50"].get<double>(), 1000.0);
    EXPECT_EQ(ticking["link"]["read_timeouts"], 0);
    const CommandResult text = hapticctl(d.socket, "status");
    EXPECT_EQ(text.exit_code, 0) << text.err;
    for (const char* line : {"state     ", "rate      ", "wake      p50 ", "compute   p50 ",
                             "link      0 reads without a sample", "device    sim device"}) {
        EXPECT_NE(("\n" + text.out).find(std::string("\n") + line), std::string::npos)
            << line << "\n"
            << text.out;
    }

    const CommandResult disarm = hapticctl(d.socket, "disarm");
    EXPECT_EQ(disarm.exit_code, 0) << disarm.err;
    EXPECT_TRUE(disarm.out.starts_with("state disabled (was ")) << disarm.out;
    const nlohmann::json disabled = status_of(d.socket);
    EXPECT_EQ(disabled["state"], "disabled");
    EXPECT_EQ(disabled["armed"], false);
    EXPECT_EQ(disabled["f_n"][0], 0.0);

    const CommandResult arm = hapticctl(d.socket, "arm");
    EXPECT_EQ(arm.exit_code, 0) << arm.err;
    EXPECT_TRUE(arm.out.starts_with("state arming") || arm.out.starts_with("state running"))
        << arm.out;

    // The jump latches a fault; with a socket the run waits, at zero force, for a reset.
    const nlohmann::json faulted =
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "fault"; });
    ASSERT_EQ(faulted["state"], "fault") << faulted.dump();
    EXPECT_EQ(faulted["faults"], nlohmann::json::array({"encoder_jump"}));
    EXPECT_EQ(faulted["f_n"][0], 0.0);
    const nlohmann::json later = status_when(d.socket, [&](const nlohmann::json& s) {
        return s["tick"] > faulted["tick"].get<int>() + 200;
    });
    EXPECT_EQ(later["state"], "fault") << "the fault did not stay latched";

    const CommandResult refused = hapticctl(d.socket, "arm");
    EXPECT_EQ(refused.exit_code, 1);
    EXPECT_NE(refused.err.find("arm refused: a fault is latched ([\"encoder_jump\"])"),
              std::string::npos)
        << refused.err;

    const CommandResult reset = hapticctl(d.socket, "reset");
    EXPECT_EQ(reset.exit_code, 0) << reset.err;
    EXPECT_TRUE(reset.out.starts_with("state arming") || reset.out.starts_with("state running"))
        << reset.out;
    EXPECT_EQ(status_of(d.socket)["faults"], nlohmann::json::array());

    const CommandResult watch = hapticctl(d.socket, "watch --count 3");
    EXPECT_EQ(watch.exit_code, 0) << watch.err;
    const std::vector<std::string> lines = lines_of_text(watch.out);
    ASSERT_EQ(lines.size(), 3u) << watch.out;
    for (const std::string& line : lines) {
        EXPECT_TRUE(line.starts_with("t ")) << line;
        EXPECT_NE(line.find(" Hz  x ["), std::string::npos) << line;
    }

    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    const nlohmann::json summary = nlohmann::json::parse(read_file(d.summary));
    EXPECT_EQ(summary["exit"], "stopped");
    EXPECT_EQ(summary["faults"], nlohmann::json::array({"encoder_jump"}));  // seen, reset
    const std::string messages = d.process.messages();
    EXPECT_NE(messages.find("hapticd: control socket " + d.socket), std::string::npos);
    EXPECT_NE(messages.find("control: disarm from pid "), std::string::npos) << messages;
    EXPECT_NE(messages.find("control: arm from pid "), std::string::npos);
    EXPECT_NE(messages.find("refused: a fault is latched"), std::string::npos);
    EXPECT_NE(messages.find("control: reset from pid "), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(d.socket)) << "the socket outlived the daemon";
}

// A reset and an arm sent together: the arm finds the fault still latched (the servo takes
// the reset at its next tick) and is accepted, because the same tick clears the latch first.
// [safety] arm_at_start = false: the run starts disabled at zero force, and pushes only once
// an operator arms it; without a control socket nobody could, so hapticd refuses to start.
TEST(HilControlSocket, ADaemonThatStartsDisarmedWaitsForArm) {
    const ScratchDir dir;
    std::string toml = config_with_room("");
    const std::string safety = "[safety]\n";
    toml.replace(toml.find(safety), safety.size(), safety + "arm_at_start = false\n");
    Daemon d(dir, "lab", ConfigText{toml});
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    // Half a second of ticks, and still disabled at zero force: the demo wall pushes at once
    // when armed (the handle starts inside it).
    const nlohmann::json waiting =
        status_when(d.socket, [](const nlohmann::json& s) { return s["t_s"] >= 0.5; });
    EXPECT_GE(waiting["t_s"].get<double>(), 0.5) << waiting.dump();
    EXPECT_EQ(waiting["state"], "disabled") << waiting.dump();
    EXPECT_EQ(waiting["armed"], false);
    EXPECT_EQ(waiting["f_n"][0], 0.0);
    EXPECT_EQ(hapticctl(d.socket, "arm").exit_code, 0);
    const nlohmann::json running =
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "running"; });
    EXPECT_EQ(running["state"], "running") << running.dump();
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();

    const CommandResult no_socket =
        run_command(shell_quote(HAPTICD_BIN) + " --no-status --lockstep --duration 1 --config " +
                    shell_quote(dir.write("nosocket.toml", toml)));
    EXPECT_EQ(no_socket.exit_code, 2) << no_socket.err;
    EXPECT_NE(no_socket.err.find("nosocket.toml: [safety] arm_at_start = false waits for "
                                 "hapticctl arm, which needs a control socket"),
              std::string::npos)
        << no_socket.err;
}

TEST(HilControlSocket, APipelinedResetThenArmIsAccepted) {
    const ScratchDir dir;
    Daemon d(dir, "lab", "[device.sim.faults]\njump_at = 0.3\njump_counts = 20000\n");
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    const nlohmann::json faulted =
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] == "fault"; });
    ASSERT_EQ(faulted["state"], "fault") << faulted.dump();
    UnixClient client(d.socket);
    ASSERT_TRUE(client.send(R"({"v":1,"id":1,"request":"reset"})"
                            "\n"
                            R"({"v":1,"id":2,"request":"arm"})"
                            "\n"));
    for (int id = 1; id <= 2; ++id) {
        const auto line = client.line();
        ASSERT_TRUE(line.has_value());
        const nlohmann::json reply = nlohmann::json::parse(*line);
        EXPECT_EQ(reply["id"], id);
        EXPECT_EQ(reply["ok"], true) << reply.dump();
    }
    const nlohmann::json after =
        status_when(d.socket, [](const nlohmann::json& s) { return s["state"] != "fault"; });
    EXPECT_TRUE(armed_state(after)) << after.dump();
    EXPECT_EQ(after["faults"], nlohmann::json::array());
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

TEST(HilControlSocket, HostileClientsGetErrorsOrDisconnectsAndTheServoNeverNotices) {
    const ScratchDir dir;
    Daemon d(dir, "lab");
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    const auto started = std::chrono::steady_clock::now();

    {  // Malformed, unknown and oversized requests.
        UnixClient client(d.socket);
        client.send(
            "{]\n{\"v\":1,\"request\":\"self-destruct\"}\n{\"v\":7,\"request\":\"status\"}\n");
        for (const char* says : {"is not JSON", "unknown request", "version 1"}) {
            const auto line = client.line();
            ASSERT_TRUE(line.has_value());
            EXPECT_NE(line->find(says), std::string::npos) << *line;
        }
        client.send(std::string(100000, 'x') + "\n");
        const auto refusal = client.line();
        ASSERT_TRUE(refusal.has_value());
        EXPECT_NE(refusal->find("at most 4096"), std::string::npos) << *refusal;
        EXPECT_TRUE(client.closed_by_peer());
    }
    // Clients that connect and never send, up to the limit and past it.
    std::vector<std::unique_ptr<UnixClient>> idle;
    idle.reserve(16);
    for (int i = 0; i < 16; ++i) idle.push_back(std::make_unique<UnixClient>(d.socket));
    {
        UnixClient one_too_many(d.socket);  // heard for a line for 1 s, then refused
        const auto refusal = one_too_many.line(std::chrono::seconds(5));
        ASSERT_TRUE(refusal.has_value());
        EXPECT_NE(refusal->find("too many clients"), std::string::npos) << *refusal;
    }
    idle.clear();
    {  // A flood from a client that reads nothing, until the daemon hangs up on it.
        std::this_thread::sleep_for(50ms);  // the idle ones' places come free
        UnixClient flooder(d.socket);
        std::string burst;
        for (int i = 0; i < 1000; ++i) burst += "{\"v\":1,\"request\":\"status\"}\n";
        bool gone = false;
        for (int round = 0; round < 20000 && !gone; ++round) gone = !flooder.send(burst);
        EXPECT_TRUE(gone) << "the daemon never disconnected a client that reads nothing";
    }
    {  // Half-closed: the request is answered, then the daemon closes.
        UnixClient half(d.socket);
        half.send("{\"v\":1,\"id\":3,\"request\":\"status\"}\n");
        half.shutdown_sending();
        const auto reply = half.line();
        ASSERT_TRUE(reply.has_value());
        EXPECT_EQ(nlohmann::json::parse(*reply)["id"], 3);
        EXPECT_TRUE(half.closed_by_peer());
    }

    {  // A slow reader: 100 requests at once, their replies read one every 2 ms: all served.
        UnixClient slow(d.socket);
        std::string burst;
        for (int i = 0; i < 100; ++i) {
            burst += "{\"v\":1,\"id\":" + std::to_string(i) + ",\"request\":\"status\"}\n";
        }
        ASSERT_TRUE(slow.send(burst));
        for (int i = 0; i < 100; ++i) {
            std::this_thread::sleep_for(2ms);
            const auto reply = slow.line();
            ASSERT_TRUE(reply.has_value()) << "reply " << i;
            const nlohmann::json answer = nlohmann::json::parse(*reply);
            EXPECT_EQ(answer["id"], i);
            EXPECT_EQ(answer["ok"], true);
        }
    }

    // Through all of it: no fault, the rate kept, and hapticctl still served.
    std::this_thread::sleep_until(started + 1500ms);
    const nlohmann::json s = status_of(d.socket);
    EXPECT_EQ(s["faults"], nlohmann::json::array()) << s.dump();
    EXPECT_NEAR(s["measured_rate_hz"].get<double>(), 1000.0, 60.0) << s.dump();
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    const nlohmann::json summary = nlohmann::json::parse(read_file(d.summary));
    EXPECT_EQ(summary["faults"], nlohmann::json::array());
    const std::string messages = d.process.messages();
    EXPECT_NE(messages.find("bytes of replies unread"), std::string::npos) << messages;
    EXPECT_NE(messages.find("clients already connected"), std::string::npos) << messages;
}

// The default config: the pen display (m = 0.1 kg, b = 2 N s/m) at 1 kHz, checked by the
// passive model, whose bound with no delay is b_c + k_c T/2 < b: k_c < 4000 N/m at b_c = 0.
TEST(HilControlSocket, ACouplingRequestIsCheckedAndRefusedWithTheVerdictWhenItFails) {
    const ScratchDir dir;
    Daemon d(dir, "lab");
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    EXPECT_EQ(status_of(d.socket)["coupling"]["stiffness"], 3600.0);  // the config's

    const CommandResult accepted = hapticctl(d.socket, "coupling 2000");
    EXPECT_EQ(accepted.exit_code, 0) << accepted.err;
    EXPECT_NE(accepted.out.find("coupling k_c 2000 N/m, b_c 0 N s/m"), std::string::npos)
        << accepted.out;
    EXPECT_NE(accepted.out.find("passive model"), std::string::npos) << accepted.out;
    const nlohmann::json now = status_when(
        d.socket, [](const nlohmann::json& s) { return s["coupling"]["stiffness"] == 2000.0; });
    EXPECT_EQ(now["coupling"]["stiffness"], 2000.0);
    EXPECT_EQ(now["coupling"]["damping"], 0.0);

    // Above the passive bound: refused with the check's verdict, the gains in force kept.
    const CommandResult unstable = hapticctl(d.socket, "coupling 4500");
    EXPECT_EQ(unstable.exit_code, 1);
    EXPECT_NE(unstable.err.find("coupling refused: "), std::string::npos) << unstable.err;
    EXPECT_NE(unstable.err.find("passive model"), std::string::npos) << unstable.err;
    // k_c T/2 + b_c = 1 + 1.5 N s/m is past b = 2 too: the damping counts.
    EXPECT_EQ(hapticctl(d.socket, "coupling 2000 1.5").exit_code, 1);
    const CommandResult out_of_range = hapticctl(d.socket, "coupling 5e9");
    EXPECT_EQ(out_of_range.exit_code, 1);
    EXPECT_NE(out_of_range.err.find("stiffness = 5e+09 is out of range"), std::string::npos)
        << out_of_range.err;
    EXPECT_EQ(status_of(d.socket)["coupling"]["stiffness"], 2000.0);

    {  // Pipelined: the second request keeps the damping the first set, taken or not.
        UnixClient raw(d.socket);
        raw.send(R"({"v":1,"id":1,"request":"coupling","stiffness":100,"damping":1.5})"
                 "\n"
                 R"({"v":1,"id":2,"request":"coupling","stiffness":200})"
                 "\n");
        const auto first = raw.line(10s);
        const auto second = raw.line(10s);
        ASSERT_TRUE(first.has_value() && second.has_value());
        EXPECT_EQ(nlohmann::json::parse(*first)["ok"], true) << *first;
        EXPECT_EQ(nlohmann::json::parse(*second)["damping"], 1.5) << *second;
    }
    for (const char* bad : {"coupling", "coupling -5", "coupling stiff", "coupling 100 -1",
                            "coupling 100 1 2", "coupling inf", "coupling 100 nan"}) {
        SCOPED_TRACE(bad);
        const CommandResult r = hapticctl(d.socket, bad);
        EXPECT_EQ(r.exit_code, 2) << r.err;
    }
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
    const std::string messages = d.process.messages();
    EXPECT_NE(messages.find("control: coupling from pid "), std::string::npos) << messages;
    EXPECT_NE(messages.find("k_c 2000 N/m, b_c 0 N s/m from the next tick"), std::string::npos)
        << messages;
}

// Two instances side by side as hapticd@lab0 and hapticd@lab1 run them: each on its own CPU
// and on its instance's socket in /run/hapticd, each keeping its rate, and each controlled
// with hapticctl -i NAME (root's: /run is root's, as it is systemd's).
TEST(HilControlSocket, TwoInstancesAreEachControlledByTheirInstanceName) {
    if (::sysconf(_SC_NPROCESSORS_ONLN) < 2) GTEST_SKIP() << "needs two CPUs";
    if (::geteuid() != 0) GTEST_SKIP() << "needs root: the instances' sockets are in /run/hapticd";
    std::filesystem::create_directories("/run/hapticd");
    const ScratchDir dir;
    // Names of this process's own, so that a second suite on the machine is not in the way.
    const std::string pid = std::to_string(::getpid());
    const std::string name_a = "test" + pid + "_a";
    const std::string name_b = "test" + pid + "_b";
    Daemon a(dir, "lab0", ConfigText{config_with_room("", "cpu = 0\n")}, instance_socket(name_a));
    Daemon b(dir, "lab1", ConfigText{config_with_room("", "cpu = 1\n")}, instance_socket(name_b));
    ASSERT_TRUE(a.process.wait_for_socket(a.socket)) << a.process.messages();
    ASSERT_TRUE(b.process.wait_for_socket(b.socket)) << b.process.messages();
    const auto status_of_instance = [](const std::string& name) {
        const CommandResult r = hapticctl_instance(name, "status --json");
        EXPECT_EQ(r.exit_code, 0) << r.err;
        return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
    };
    // Each keeps its rate while the other runs: the measured rate (ticks over the last second
    // of wall time) within 2 % of 1000 Hz, in a second that no stall of the shared VM spoils.
    for (const std::string& name : {name_a, name_b}) {
        SCOPED_TRACE(name);
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        nlohmann::json s = status_of_instance(name);
        while (!s.is_null() && std::abs(s["measured_rate_hz"].get<double>() - 1000.0) > 20.0 &&
               std::chrono::steady_clock::now() < deadline) {
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
            s = status_of_instance(name);
        }
        ASSERT_FALSE(s.is_null());
        EXPECT_NEAR(s["measured_rate_hz"].get<double>(), 1000.0, 20.0) << s.dump();
        EXPECT_EQ(s["rate_hz"], 1000.0);
    }
    EXPECT_EQ(hapticctl_instance(name_a, "disarm").exit_code, 0);
    EXPECT_EQ(status_of_instance(name_a)["state"], "disabled");
    EXPECT_TRUE(armed_state(status_of_instance(name_b)));
    EXPECT_TRUE(
        status_of_instance(name_a)["config_path"].get<std::string>().ends_with("/lab0.toml"));
    EXPECT_TRUE(
        status_of_instance(name_b)["config_path"].get<std::string>().ends_with("/lab1.toml"));
    // A third on a socket that one of them serves is refused, and harms neither.
    const CommandResult third = run_command(
        shell_quote(HAPTICD_BIN) + " --no-status --duration 1 --socket " + shell_quote(a.socket));
    EXPECT_EQ(third.exit_code, 2);
    EXPECT_NE(third.err.find("is in use: another hapticd answers on it"), std::string::npos)
        << third.err;
    EXPECT_EQ(status_of_instance(name_a)["state"], "disabled");
    EXPECT_EQ(a.process.stop(), 0) << a.process.messages();
    EXPECT_EQ(b.process.stop(), 0) << b.process.messages();
    // Each removed its socket as it ended; the instance name then reaches nobody.
    EXPECT_FALSE(std::filesystem::exists(a.socket));
    EXPECT_FALSE(std::filesystem::exists(b.socket));
    const CommandResult gone = hapticctl_instance(name_a, "status");
    EXPECT_EQ(gone.exit_code, 1);
    EXPECT_NE(gone.err.find(instance_socket(name_a)), std::string::npos) << gone.err;
}

std::vector<std::string> fields_of(const std::string& row) {
    std::vector<std::string> fields;
    std::istringstream in(row);
    for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
    if (!row.empty() && row.back() == ',') fields.emplace_back();  // an empty last column
    return fields;
}

// hapticctl stream: the --log's column names, a row per event at the rate asked, the ticks
// moving on with the servo's; and a reader that leaves ends it quietly.
TEST(HilControlSocket, HapticctlStreamWritesTheTelemetryAsCsv) {
    const ScratchDir dir;
    Daemon daemon(dir, "lab0", "");
    ASSERT_TRUE(daemon.process.wait_for_socket(daemon.socket)) << daemon.process.messages();
    const int axes = status_of(daemon.socket)["axes"].get<int>();
    const CommandResult r = hapticctl(daemon.socket, "stream --rate 50 --count 20");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::vector<std::string> lines = lines_of_text(r.out);
    ASSERT_EQ(lines.size(), 21u) << r.out;
    std::string header = "tick,t_s,state";
    for (const char* column : {"x", "xe", "f"}) {
        for (int i = 0; i < axes; ++i) {
            header += "," + std::string(column) + std::to_string(i) +
                      (std::string(column) == "f" ? "_n" : "_m");
        }
    }
    EXPECT_EQ(lines[0], header + ",faults");
    std::uint64_t first_tick = 0;
    std::uint64_t last_tick = 0;
    for (std::size_t i = 1; i < lines.size(); ++i) {
        const std::vector<std::string> fields = fields_of(lines[i]);
        ASSERT_EQ(fields.size(), static_cast<std::size_t>(4 + 3 * axes)) << lines[i];
        const std::uint64_t tick = std::stoull(fields[0]);
        EXPECT_GE(tick, last_tick) << lines[i];
        if (i == 1) first_tick = tick;
        last_tick = tick;
        EXPECT_TRUE(fields[2] == "arming" || fields[2] == "running") << lines[i];
        EXPECT_EQ(fields.back(), "") << "a fault on the default scene: " << lines[i];
    }
    // 19 periods of 20 ms at 1 kHz: about 380 ticks apart (a shared machine's wakes vary).
    EXPECT_GT(last_tick - first_tick, 250u);
    EXPECT_LT(last_tick - first_tick, 1500u);
    const CommandResult piped =
        run_command("bash -c 'set -o pipefail; \"" + std::string(HAPTICCTL_BIN) + "\" --socket \"" +
                    daemon.socket + "\" stream --rate 100 | head -n 3'");
    EXPECT_EQ(piped.exit_code, 0) << piped.err;
    EXPECT_EQ(lines_of_text(piped.out).size(), 3u);
    EXPECT_EQ(piped.err, "");
    // At a slow rate, SIGINT ends the wait for the next event at once.
    const auto before = std::chrono::steady_clock::now();
    const CommandResult slow =
        run_command("timeout --preserve-status -s INT 0.5 " + shell_quote(HAPTICCTL_BIN) +
                    " --socket " + shell_quote(daemon.socket) + " stream --rate 0.01");
    EXPECT_EQ(slow.exit_code, 0) << slow.err;
    EXPECT_LT(std::chrono::steady_clock::now() - before, 3s) << "SIGINT waited for an event";
    EXPECT_EQ(lines_of_text(slow.out).size(), 2u) << slow.out;  // the header and the first row
    EXPECT_EQ(daemon.process.stop(), 0) << daemon.process.messages();
}

// hapticctl record: every tick from the start to the stop in a --log file the product's reader
// reads, status naming the file meanwhile; refusals with exit 1; and a recording the run's end
// interrupts is closed whole.
TEST(HilControlSocket, HapticctlRecordsEveryTickLosslessly) {
    const ScratchDir dir;
    Daemon daemon(dir, "lab0", "");
    ASSERT_TRUE(daemon.process.wait_for_socket(daemon.socket)) << daemon.process.messages();
    const std::string file = dir.file("take1.csv");
    const CommandResult started = hapticctl(daemon.socket, "record start " + shell_quote(file));
    ASSERT_EQ(started.exit_code, 0) << started.err;
    EXPECT_NE(started.out.find("recording to " + file + " from tick "), std::string::npos)
        << started.out;
    EXPECT_EQ(status_of(daemon.socket)["recording"], file);
    const CommandResult again = hapticctl(daemon.socket, "record start " + dir.file("take2.csv"));
    EXPECT_EQ(again.exit_code, 1);
    EXPECT_NE(again.err.find("already recording to " + file), std::string::npos) << again.err;
    std::this_thread::sleep_for(500ms);
    const CommandResult stopped = hapticctl(daemon.socket, "record stop");
    ASSERT_EQ(stopped.exit_code, 0) << stopped.err;
    EXPECT_NE(stopped.out.find("records, none lost"), std::string::npos) << stopped.out;
    EXPECT_TRUE(status_of(daemon.socket)["recording"].is_null());
    const TelemetryLog log = read_telemetry(file);
    EXPECT_EQ(stopped.out, file + ": " + std::to_string(log.rows()) + " records, none lost\n");
    EXPECT_GT(log.rows(), 300u) << "0.5 s at 1 kHz";
    const std::vector<double>& tick = log.column("tick");
    for (std::size_t i = 1; i < tick.size(); ++i) {
        ASSERT_EQ(tick[i], tick[i - 1] + 1.0) << "tick lost at row " << i;
    }
    const CommandResult not_recording = hapticctl(daemon.socket, "record stop");
    EXPECT_EQ(not_recording.exit_code, 1);
    EXPECT_NE(not_recording.err.find("not recording"), std::string::npos) << not_recording.err;
    const CommandResult over = hapticctl(daemon.socket, "record start " + shell_quote(file));
    EXPECT_EQ(over.exit_code, 1);
    EXPECT_NE(over.err.find("it exists, and no file is ever overwritten"), std::string::npos)
        << over.err;
    // A relative FILE is hapticctl's working directory's, as a shell user means it.
    const CommandResult relative =
        run_command("cd " + shell_quote(dir.path().string()) + " && " + shell_quote(HAPTICCTL_BIN) +
                    " --socket " + shell_quote(daemon.socket) + " record start take3.csv");
    ASSERT_EQ(relative.exit_code, 0) << relative.err;
    EXPECT_NE(relative.out.find(dir.file("take3.csv")), std::string::npos) << relative.out;
    // The recording begins at the tick after the request; give the loop ticks to record before
    // the run ends, or a stop that races the first tick would leave a whole but empty file.
    std::this_thread::sleep_for(200ms);
    EXPECT_EQ(daemon.process.stop(), 0) << daemon.process.messages();
    EXPECT_NE(daemon.process.messages().find("take3.csv closed: "), std::string::npos)
        << daemon.process.messages();
    EXPECT_GT(read_telemetry(dir.file("take3.csv")).rows(), 0u);
}

// hapticctl mark: each marker and each change of gains is numbered, stamped on every record
// from the servo's next tick on and named in a "# mark N:" line before the first of them; a
// recording's preamble names the gains, the verdict and the scene in force as it starts, and
// plot-run reads k_c, and its change, from the recording alone.
TEST(HilControlSocket, HapticctlMarksTrialsInTheRecordingWhosePreambleNamesTheGains) {
    const ScratchDir dir;
    Daemon daemon(dir, "lab0", "");
    ASSERT_TRUE(daemon.process.wait_for_socket(daemon.socket)) << daemon.process.messages();
    const std::string first = dir.file("trials.csv");
    // Each step waits for the servo to be two ticks past the request, so that each mark has
    // records of its own whatever the host's timing; the recording, rows before the first.
    const auto step = [&](const std::string& arguments) {
        CommandResult r = hapticctl(daemon.socket, arguments);
        EXPECT_EQ(r.exit_code, 0) << arguments << ": " << r.err;
        const auto tick = status_of(daemon.socket)["tick"].get<std::uint64_t>();
        status_when(daemon.socket, [tick](const nlohmann::json& s) {
            return s["tick"].get<std::uint64_t>() >= tick + 3;
        });
        return r;
    };
    step("record start " + shell_quote(first));
    const CommandResult a = step("mark 'trial A'");
    EXPECT_EQ(a.out.rfind("mark 1 from the tick after ", 0), 0u) << a.out;
    step("coupling 1999.123456789");  // more digits than the journal's six: the note keeps all
    step("mark 'trial B, caf\xc3\xa9'");
    ASSERT_EQ(hapticctl(daemon.socket, "record stop").exit_code, 0);

    const TelemetryLog log = read_telemetry(first);
    EXPECT_EQ(log.preamble("coupling_stiffness_n_per_m"), "3600");  // the config's, at the start
    EXPECT_NE(log.preamble("stability").find("passive model"), std::string::npos);
    EXPECT_EQ(log.preamble("scene").rfind("demo-wall (impedance, ", 0), 0u)
        << log.preamble("scene");
    ASSERT_EQ(log.marks().size(), 3u);
    EXPECT_EQ(log.marks()[0].text, "trial A");
    EXPECT_EQ(log.marks()[1].text.rfind("coupling k_c 1999.123456789 N/m, b_c 0 N s/m; ", 0), 0u)
        << log.marks()[1].text;
    EXPECT_NE(log.marks()[1].text.find("passive model"), std::string::npos);
    EXPECT_EQ(log.marks()[2].text, "trial B, caf\xc3\xa9");
    const std::vector<double>& mark = log.column("mark");
    EXPECT_EQ(mark.front(), 0.0);
    EXPECT_TRUE(std::is_sorted(mark.begin(), mark.end()));
    for (const tune::TelemetryMark& m : log.marks()) {
        SCOPED_TRACE(m.number);
        ASSERT_LT(m.row, log.rows());
        ASSERT_GT(m.row, 0u);
        EXPECT_EQ(mark[m.row], static_cast<double>(m.number));  // the first row that carries it
        EXPECT_EQ(mark[m.row - 1], static_cast<double>(m.number - 1));
    }

    // A second recording starts in trial 3, with the gains in force then.
    const std::string second = dir.file("later.csv");
    ASSERT_EQ(hapticctl(daemon.socket, "record start " + shell_quote(second)).exit_code, 0);
    step("status");
    ASSERT_EQ(hapticctl(daemon.socket, "record stop").exit_code, 0);
    const TelemetryLog later = read_telemetry(second);
    EXPECT_EQ(later.preamble("coupling_stiffness_n_per_m"), "1999.123456789");
    ASSERT_EQ(later.marks().size(), 1u);
    EXPECT_EQ(later.marks()[0].number, 3u);
    EXPECT_EQ(later.marks()[0].row, 0u);

    // plot-run takes k_c from the recording: 3600 N/m, then the coupling mark's, exactly.
    const CommandResult judged =
        run_command(shell_quote(HAPTIC_TUNE_BIN) + " plot-run --json " + shell_quote(first));
    ASSERT_EQ(judged.exit_code, 0) << judged.err;
    const nlohmann::json j = nlohmann::json::parse(judged.out);
    EXPECT_EQ(j.at("coupling_stiffness_n_per_m"), 3600.0);
    EXPECT_EQ(j.at("coupling_stiffness_source"), "the log's preamble and its coupling marks");
    ASSERT_EQ(j.at("coupling_stiffness_changes").size(), 2u);
    EXPECT_EQ(j.at("coupling_stiffness_changes")[1].at("stiffness_n_per_m"), 1999.123456789);

    // Marks a client may not make: each refused, naming why.
    for (const auto& [arguments, says] : std::vector<std::pair<std::string, std::string>>{
             {"mark ''", "empty"},
             {"mark " + std::string(201, 'x'), "201 bytes: allowed 1 to 200"},
             {"mark $'two\\nlines'", "a control character at byte 4"}}) {
        const CommandResult r =
            run_command("bash -c " + shell_quote(shell_quote(HAPTICCTL_BIN) + " --socket " +
                                                 shell_quote(daemon.socket) + " " + arguments));
        EXPECT_EQ(r.exit_code, 2) << arguments;
        EXPECT_NE(r.err.find(says), std::string::npos) << arguments << ": " << r.err;
    }
    UnixClient raw(daemon.socket);
    raw.send(R"({"v":1,"id":9,"request":"mark","text":"a\u001b[2Jb"})"
             "\n");
    const auto refused = raw.line(10s);
    ASSERT_TRUE(refused.has_value());
    EXPECT_NE(refused->find("a control character at byte 2"), std::string::npos) << *refused;
    EXPECT_EQ(daemon.process.stop(), 0) << daemon.process.messages();
    EXPECT_NE(daemon.process.messages().find("control: mark 1 from pid "), std::string::npos)
        << daemon.process.messages();
}

struct BadUsage {
    std::string arguments;
    int exit_code;
    std::string says;
};

TEST(HilControlSocket, HapticctlRefusesBadUsageWith2AndAnUnreachableDaemonWith1) {
    const ScratchDir dir;
    const std::string nowhere = dir.file("nobody.sock");
    const BadUsage cases[] = {
        {"status", 2, "give -i NAME (hapticd@NAME) or --socket PATH"},
        {"-i 'a/b' status", 2, "-i \"a/b\": an instance name may hold only"},
        {"-i '' status", 2, "-i \"\": an instance name must be 1 to 64 characters"},
        {"-i lab --socket " + nowhere + " status", 2, "excludes"},
        {"--socket " + nowhere, 2, "no command: one of status, watch, arm, disarm, reset"},
        {"--socket " + nowhere + " launch", 2, "\"launch\" is not a command: one of status"},
        {"--socket " + nowhere + " watch --count -1", 2, "--count"},
        {"--socket " + nowhere + " status --rate 5", 2, "--rate"},
        {"--socket " + nowhere + " stream --rate 0", 2, "--rate"},
        {"--socket " + nowhere + " stream --rate 101", 2, "--rate"},
        {"--socket " + nowhere + " stream --rate fast", 2, "--rate"},
        {"--socket " + nowhere + " stream --count -2", 2, "--count"},
        {"--socket " + nowhere + " record", 2, "record needs start FILE or stop"},
        {"--socket " + nowhere + " record start", 2, "FILE"},
        {"--socket " + nowhere + " record begin x", 2, "record \"begin\": give start FILE or stop"},
        {"--socket " + nowhere + " coupling inf", 2, "K: \"inf\" is not a finite number >= 0"},
        {"--socket " + nowhere + " coupling 100 nan", 2, "B: \"nan\" is not a finite number >= 0"},
        {"--socket " + nowhere + " coupling -5", 2, "-5"},
        {"--socket " + nowhere + " coupling stiff", 2, "K: \"stiff\" is not a finite number"},
        {"--socket '' status", 2, "--socket: \"\" is 0 bytes: a socket path is 1 to 107 bytes"},
        {"--socket " + std::string(120, 's') + " status", 2,
         "is 120 bytes: a socket path is 1 to 107 bytes"},
        {"--socket " + nowhere + " record start ''", 2,
         "the path is empty: name the file to create"},
        {"--socket " + nowhere + " scene ''", 2, "the path is empty: name the scene file"},
        {"--socket " + nowhere + " scene", 2, "FILE"},
        {"--socket " + nowhere + " status", 1, "cannot connect to " + nowhere + ": no hapticd"},
        {"-i no-such-instance-here arm", 1,
         "cannot connect to /run/hapticd/no-such-instance-here.sock"},
    };
    for (const BadUsage& c : cases) {
        SCOPED_TRACE(c.arguments);
        const CommandResult r = run_command(shell_quote(HAPTICCTL_BIN) + " " + c.arguments);
        EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    }
    for (const char* command : {"status", "watch", "arm", "disarm", "reset", "coupling", "stream",
                                "record", "scene", "identify"}) {
        const CommandResult help =
            run_command(shell_quote(HAPTICCTL_BIN) + " " + command + " --help");
        EXPECT_EQ(help.exit_code, 0) << command;
        EXPECT_NE(help.out.find("Usage"), std::string::npos) << command;
    }
}

TEST(HilControlSocket, HapticdRefusesASocketPathItCannotServe) {
    const ScratchDir dir;
    const std::string file = dir.write("plain.txt", "keep me\n");
    const struct {
        std::string path;
        std::string says;
    } cases[] = {
        {"''", "--socket \"\": the path is empty"},
        {shell_quote(file), "exists and is not a socket"},
        {shell_quote(dir.file("no/such/dir/c.sock")), "bind(): No such file or directory"},
        {shell_quote(dir.file(std::string(120, 's'))), "a path of 1 to 107 bytes"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.path);
        const CommandResult r = run_command(
            shell_quote(HAPTICD_BIN) + " --no-status --lockstep --duration 1 --socket " + c.path);
        EXPECT_EQ(r.exit_code, 2) << r.err;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    }
    EXPECT_EQ(read_file(file), "keep me\n");
}

}  // namespace
}  // namespace hapticd::testing
