// hapticctl status's text (tools/hapticctl/status_text.cpp), in particular its frames line:
// every link count the daemon sends, and a daemon of an earlier release (still running after
// an upgrade, which restarts no instance) that sends fewer is shown, not refused.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "status_text.hpp"

namespace hapticd::ctl {
namespace {

nlohmann::json status_with_link(const nlohmann::json& link) {
    return {{"state", "running"},
            {"soft_start_scale", 1.0},
            {"tick", 12000},
            {"t_s", 12.0},
            {"measured_rate_hz", 1000.0},
            {"rate_hz", 1000.0},
            {"x_m", {0.001}},
            {"xe_m", {0.0}},
            {"f_n", {2.5}},
            {"faults", nlohmann::json::array()},
            {"overruns", 3},
            {"wake_latency_us", {{"p50", 15.0}, {"p99", 40.0}, {"max", 90.0}}},
            {"tick_compute_us", {{"p50", 0.7}, {"p99", 2.5}, {"max", 9.0}}},
            {"link", link},
            {"device", "usb device 1209:0001"},
            {"config_path", "/etc/hapticd/lab0.toml"}};
}

nlohmann::json abi4_link() {
    return {{"read_timeouts", 7},     {"link_recoveries", 1},
            {"counted", true},        {"frames_sent", 1000},
            {"frames_received", 990}, {"bad_frames", 3},
            {"transfer_errors", 4},   {"reply_timeouts", 7},
            {"missed_samples", 5},    {"late", 6},
            {"duplicate", 8},         {"device_errors", 9},
            {"disconnects", 1},       {"reconnects", 1}};
}

std::string frames_line(const std::string& text) {
    const std::size_t at = text.find("\nframes    ");
    if (at == std::string::npos) return "";
    return text.substr(at + 1, text.find('\n', at + 1) - at - 1);
}

TEST(HapticctlStatusText, TheFramesLineSaysEveryLinkCount) {
    nlohmann::json link = abi4_link();
    link["wrong_session"] = 10;
    link["unexpected"] = 11;
    link["out_of_step"] = 12;
    EXPECT_EQ(frames_line(status_text(status_with_link(link))),
              "frames    1000 sent, 990 received, 3 bad, 4 transfer errors, 7 reply timeouts, "
              "5 samples missed, 6 late, 8 duplicate, 9 device errors, 1 disconnects, "
              "1 reconnects, 10 of another session, 11 unexpected, 12 out of step");
}

TEST(HapticctlStatusText, ADaemonOfAnEarlierReleaseWithoutTheLaterCountsIsShownWithoutThem) {
    const std::string text = status_text(status_with_link(abi4_link()));
    EXPECT_EQ(frames_line(text),
              "frames    1000 sent, 990 received, 3 bad, 4 transfer errors, 7 reply timeouts, "
              "5 samples missed, 6 late, 8 duplicate, 9 device errors, 1 disconnects, "
              "1 reconnects");
    EXPECT_NE(text.find("link      7 reads without a sample, 1 recoveries\n"), std::string::npos)
        << text;
}

TEST(HapticctlStatusText, ADeviceWithoutCountsHasNoFramesLine) {
    nlohmann::json link = abi4_link();
    link["counted"] = false;
    EXPECT_EQ(frames_line(status_text(status_with_link(link))), "");
}

}  // namespace
}  // namespace hapticd::ctl

namespace hapticd::ctl {
namespace {

// [servo] name heads the text when the daemon has one; a daemon without one (or of an
// earlier release, which sends no name) shows no line for it.
TEST(HapticctlStatusText, TheInstanceNameHeadsTheText) {
    nlohmann::json status = status_with_link(abi4_link());
    EXPECT_EQ(status_text(status).rfind("state     running", 0), 0u);
    status["name"] = "";
    EXPECT_EQ(status_text(status).rfind("state     running", 0), 0u);
    status["name"] = "left arm";
    EXPECT_EQ(status_text(status).rfind("name      left arm\nstate     running", 0), 0u)
        << status_text(status);
}

std::string line_of(const std::string& text, const std::string& label) {
    const std::size_t at = text.find("\n" + label);
    if (at == std::string::npos) return "";
    return text.substr(at + 1, text.find('\n', at + 1) - at - 1);
}

TEST(HapticctlStatusText, AnExternalWorldAndAFailedWorldAreShownWithWhy) {
    nlohmann::json s = status_with_link(abi4_link());
    EXPECT_EQ(line_of(status_text(s), "world     "), "");  // hapticd's own scene
    s["external_world"] = {{"state", "stale"},
                           {"why",
                            "no update from the world for 0.25 s: the tool holds, and "
                            "its force ramps to zero"},
                           {"update", 41},
                           {"since_update_s", 0.25},
                           {"stale_episodes", 1},
                           {"rejected_updates", 0},
                           {"energy_j", 0.5},
                           {"energy_removed_j", 0.125}};
    EXPECT_EQ(line_of(status_text(s), "world     "),
              "world     stale, update 41, stale 1 times, 0.125000 J removed by the passivity "
              "controller: no update from the world for 0.25 s: the tool holds, and its force "
              "ramps to zero");
    s["environment_failure"] = "evaluate() returned 7";
    EXPECT_EQ(line_of(status_text(s), "failure   "), "failure   evaluate() returned 7");
    s["environment_failure"] = nullptr;
    EXPECT_EQ(line_of(status_text(s), "failure   "), "");
}

}  // namespace
}  // namespace hapticd::ctl
