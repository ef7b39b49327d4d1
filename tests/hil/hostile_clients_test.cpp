// Every disarm gets through while hostile or careless clients storm a running daemon (issue
// 28, item 1; docs/control.md, "Limits"): clients that hold a place each and keep a request
// going, subscribers at 100 Hz that never read, slow readers, and a thread that connects
// without pause, all at once, while an operator runs `hapticctl disarm` again and again. The
// servo does not notice: no fault, its rate kept.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "control_daemon.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "unix_client.hpp"

namespace hapticd::testing {
namespace {

using namespace std::chrono_literals;

const std::string kStatus = R"({"v":1,"request":"status"})"
                            "\n";

// Runs `body(stop)` on its own thread until stop, reconnecting whenever the daemon closes it.
template <typename Body>
std::thread storm(const std::string& socket, std::atomic<bool>& stop, Body body) {
    return std::thread([&socket, &stop, body] {
        while (!stop.load()) {
            try {
                UnixClient client(socket);
                body(client, stop);
            } catch (const std::exception&) {  // refused or broken: connect again
                std::this_thread::sleep_for(1ms);
            }
        }
    });
}

TEST(HilHostileClients, EveryDisarmGetsThroughEveryStormAtOnce) {
    const ScratchDir dir;
    Daemon d(dir, "lab");
    ASSERT_TRUE(d.process.wait_for_socket(d.socket)) << d.process.messages();
    ASSERT_TRUE(armed_state(status_when(d.socket, armed_state)));
    std::atomic<bool> stop{false};
    std::vector<std::thread> storms;
    storms.reserve(17);
    for (int i = 0; i < 8; ++i) {  // busy: a request always going
        storms.push_back(storm(d.socket, stop, [](UnixClient& c, std::atomic<bool>& s) {
            while (!s.load() && c.send(kStatus) && c.line(1000ms)) {
            }
        }));
    }
    for (int i = 0; i < 4; ++i) {  // streams at 100 Hz that nobody reads
        storms.push_back(storm(d.socket, stop, [](UnixClient& c, std::atomic<bool>& s) {
            if (!c.send(R"({"v":1,"request":"subscribe","rate_hz":100})"
                        "\n")) {
                return;
            }
            while (!s.load() && !c.closed_by_peer(50ms)) {
            }
        }));
    }
    for (int i = 0; i < 4; ++i) {  // slow readers: a burst, then a line every 50 ms
        storms.push_back(storm(d.socket, stop, [](UnixClient& c, std::atomic<bool>& s) {
            std::string burst;
            for (int k = 0; k < 200; ++k) burst += kStatus;
            if (!c.send(burst)) return;
            while (!s.load() && c.line(1000ms)) std::this_thread::sleep_for(50ms);
        }));
    }
    storms.push_back(std::thread([&] {  // connects without pause, says nothing
        while (!stop.load()) {
            try {
                const UnixClient c(d.socket);
            } catch (const std::exception&) {
            }
        }
    }));
    std::this_thread::sleep_for(300ms);  // every storm under way

    int carried_out = 0;
    for (int k = 0; k < 10; ++k) {
        const CommandResult disarmed = hapticctl(d.socket, "disarm");
        EXPECT_EQ(disarmed.exit_code, 0) << "disarm " << k << ": " << disarmed.err;
        carried_out += disarmed.exit_code == 0 ? 1 : 0;
        std::this_thread::sleep_for(100ms);
    }
    stop = true;
    for (std::thread& t : storms) t.join();
    EXPECT_EQ(carried_out, 10);

    const nlohmann::json s = status_of(d.socket);
    EXPECT_EQ(s["state"], "disabled") << s.dump();
    EXPECT_EQ(s["faults"], nlohmann::json::array()) << s.dump();
    EXPECT_EQ(d.process.stop(), 0) << d.process.messages();
}

}  // namespace
}  // namespace hapticd::testing
