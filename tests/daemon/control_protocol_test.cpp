// The control protocol's lines (docs/control.md, "Lines"): what parses, and that every
// refusal names the field and the value; and the status body's link counts.
#include "hapticd/daemon/control_protocol.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>

#include "hapticd/device/device.hpp"
#include "socket/requests.hpp"

namespace hapticd::daemon::control_socket {
namespace {

TEST(DaemonControlProtocol, EachRequestParsesWithItsId) {
    for (const RequestKind kind :
         {RequestKind::status, RequestKind::arm, RequestKind::disarm, RequestKind::reset}) {
        const std::string line = request_line(kind, 42);
        ASSERT_EQ(line.back(), '\n');
        const ParsedRequest parsed = parse_request(line.substr(0, line.size() - 1));
        ASSERT_TRUE(parsed.request.has_value()) << parsed.error;
        EXPECT_EQ(parsed.request->kind, kind);
        EXPECT_EQ(parsed.request->id, 42);
    }
    const ParsedRequest text_id = parse_request(R"({"v":1,"id":"a7","request":"status"})");
    ASSERT_TRUE(text_id.request.has_value());
    EXPECT_EQ(text_id.request->id, "a7");
    const ParsedRequest no_id = parse_request(R"({"v":1,"request":"arm"})");
    ASSERT_TRUE(no_id.request.has_value());
    EXPECT_TRUE(no_id.request->id.is_null());
}

struct Refusal {
    std::string line;
    std::string says;  // a part of the error
};

// Each line is refused, and the error says what the case expects.
template <std::size_t N>
void expect_refused(const Refusal (&refusals)[N]) {
    for (const Refusal& r : refusals) {
        SCOPED_TRACE(r.line.substr(0, 80));
        const ParsedRequest parsed = parse_request(r.line);
        EXPECT_FALSE(parsed.request.has_value());
        EXPECT_NE(parsed.error.find(r.says), std::string::npos) << parsed.error;
    }
}

TEST(DaemonControlProtocol, EveryBadLineIsRefusedNamingWhatIsWrong) {
    const Refusal refusals[] = {
        {"status", "is not JSON"},
        {"{\"v\":1,", "is not JSON"},
        {"[1,2]", "[1,2] is not a JSON object"},
        {R"({"request":"status"})", "\"v\" is missing"},
        {R"({"v":2,"request":"status"})",
         "\"v\" = 2: this hapticd speaks control protocol version 1"},
        {R"({"v":"1","request":"status"})", "\"v\" = \"1\""},
        {R"({"v":1.5,"request":"status"})", "\"v\" = 1.5"},
        {R"({"v":1})", "\"request\" is missing: one of status, arm, disarm, reset"},
        {R"({"v":1,"request":3})", "\"request\" = 3 is not a string"},
        {R"({"v":1,"request":"launch"})", "unknown request \"launch\": one of status, arm"},
        {R"({"v":1,"request":"status","rate":5})", "unknown field \"rate\" in a \"status\""},
        {R"({"v":1,"id":[1],"request":"status"})", "\"id\" = [1]: must be an integer, a string"},
        {R"({"v":1,"id":1.5,"request":"status"})", "\"id\" = 1.5"},
        // nlohmann's reader stops at a NUL: the line would be read as a disarm.
        {std::string(R"({"v":1,"request":"disarm"})") + '\0' + R"({"v":1,"request":"arm"})",
         "the request holds a NUL byte (byte 27 of the line)"},
    };
    expect_refused(refusals);
}

TEST(DaemonControlProtocol, ACouplingRequestCarriesItsGains) {
    const Request both{.kind = RequestKind::coupling,
                       .id = 3,
                       .stiffness_n_per_m = 2500.0,
                       .damping_n_s_per_m = 0.5};
    const std::string line = request_line(both);
    const ParsedRequest parsed = parse_request(line.substr(0, line.size() - 1));
    ASSERT_TRUE(parsed.request.has_value()) << parsed.error;
    EXPECT_EQ(parsed.request->kind, RequestKind::coupling);
    EXPECT_EQ(parsed.request->stiffness_n_per_m, 2500.0);
    EXPECT_EQ(parsed.request->damping_n_s_per_m, 0.5);
    const ParsedRequest stiffness_only =
        parse_request(R"({"v":1,"request":"coupling","stiffness":100})");
    ASSERT_TRUE(stiffness_only.request.has_value()) << stiffness_only.error;
    EXPECT_FALSE(stiffness_only.request->damping_n_s_per_m.has_value());

    const Refusal refusals[] = {
        {R"({"v":1,"request":"coupling"})", "\"stiffness\" is missing"},
        {R"({"v":1,"request":"coupling","stiffness":"stiff"})",
         "\"stiffness\" = \"stiff\": must be a finite number"},
        // JSON has no infinity: a number past double's range is no JSON at all.
        {R"({"v":1,"request":"coupling","stiffness":1e999})", "is not JSON"},
        {R"({"v":1,"request":"coupling","stiffness":1,"damping":null})",
         "\"damping\" = null: must be a finite number"},
        {R"({"v":1,"request":"coupling","stiffness":1,"mass":2})",
         "unknown field \"mass\" in a \"coupling\" request: it takes only v, id, request, "
         "stiffness, damping"},
        {R"({"v":1,"request":"status","stiffness":1})", "unknown field \"stiffness\""},
    };
    expect_refused(refusals);
}

TEST(DaemonControlProtocol, ASubscriptionCarriesItsRateWithinItsRange) {
    const ParsedRequest plain = parse_request(R"({"v":1,"request":"subscribe"})");
    ASSERT_TRUE(plain.request.has_value()) << plain.error;
    EXPECT_EQ(plain.request->kind, RequestKind::subscribe);
    EXPECT_EQ(plain.request->rate_hz, kDefaultSubscribeRateHz);
    const Request fast{.kind = RequestKind::subscribe, .id = 4, .rate_hz = 100.0};
    const std::string line = request_line(fast);
    const ParsedRequest parsed = parse_request(line.substr(0, line.size() - 1));
    ASSERT_TRUE(parsed.request.has_value()) << parsed.error;
    EXPECT_EQ(parsed.request->rate_hz, 100.0);
    const ParsedRequest off = parse_request(R"({"v":1,"request":"unsubscribe"})");
    ASSERT_TRUE(off.request.has_value()) << off.error;
    EXPECT_EQ(off.request->kind, RequestKind::unsubscribe);

    const Refusal refusals[] = {
        {R"({"v":1,"request":"subscribe","rate_hz":0})",
         "\"rate_hz\" = 0: allowed >= 0.001 and <= 100 (events a second)"},
        // Its period (1 / rate_hz) overflowed the server's clock below about 1e-10.
        {R"({"v":1,"request":"subscribe","rate_hz":1e-12})", "\"rate_hz\" = 1e-12: allowed"},
        {R"({"v":1,"request":"subscribe","rate_hz":0.0009})", "\"rate_hz\" = 0.0009: allowed"},
        {R"({"v":1,"request":"subscribe","rate_hz":100.5})", "\"rate_hz\" = 100.5: allowed"},
        {R"({"v":1,"request":"subscribe","rate_hz":-3})", "\"rate_hz\" = -3: allowed"},
        {R"({"v":1,"request":"subscribe","rate_hz":"fast"})",
         "\"rate_hz\" = \"fast\": must be a finite number"},
        {R"({"v":1,"request":"subscribe","rate":5})",
         "unknown field \"rate\" in a \"subscribe\" request: it takes only v, id, request, "
         "rate_hz"},
        {R"({"v":1,"request":"unsubscribe","rate_hz":5})", "unknown field \"rate_hz\""},
    };
    expect_refused(refusals);
    const nlohmann::json event = nlohmann::json::parse(event_line("telemetry", {{"tick", 5}}));
    EXPECT_EQ(event["v"], kProtocolVersion);
    EXPECT_EQ(event["event"], "telemetry");
    EXPECT_EQ(event["tick"], 5);
    EXPECT_FALSE(event.contains("ok"));
}

TEST(DaemonControlProtocol, ARecordingNamesAnAbsolutePath) {
    const Request start{.kind = RequestKind::record_start, .id = 2, .path = "/var/log/run 1.csv"};
    const std::string line = request_line(start);
    const ParsedRequest parsed = parse_request(line.substr(0, line.size() - 1));
    ASSERT_TRUE(parsed.request.has_value()) << parsed.error;
    EXPECT_EQ(parsed.request->kind, RequestKind::record_start);
    EXPECT_EQ(parsed.request->path, "/var/log/run 1.csv");
    // A name alone: the daemon makes it in its outputs directory (docs/control.md, "Paths and
    // strings").
    const ParsedRequest name = parse_request(R"({"v":1,"request":"record_start","path":"a.csv"})");
    ASSERT_TRUE(name.request.has_value()) << name.error;
    EXPECT_EQ(name.request->path, "a.csv");
    const ParsedRequest stop = parse_request(R"({"v":1,"request":"record_stop"})");
    ASSERT_TRUE(stop.request.has_value()) << stop.error;
    EXPECT_EQ(stop.request->kind, RequestKind::record_stop);

    const std::string too_long = "/" + std::string(kMaxRequestPathBytes, 'a');
    const Refusal refusals[] = {
        {R"({"v":1,"request":"record_start"})", "\"path\" is missing"},
        {R"({"v":1,"request":"record_start","path":7})", "\"path\" = 7: must be a string"},
        {R"({"v":1,"request":"record_start","path":""})",
         "\"path\" = \"\": a file name, or an absolute path of at most 4095 bytes, is needed"},
        {R"({"v":1,"request":"record_start","path":"/a\u0000b"})",
         "\"path\" = \"/a\\u0000b\": holds a control character: allowed a path without them"},
        {R"({"v":1,"request":"record_start","path":"/a\n<0>b"})", "holds a control character"},
        {R"({"v":1,"request":"record_start","path":")" + too_long + R"("})", "a file name, or"},
        {R"({"v":1,"request":"record_stop","path":"/x"})",
         "unknown field \"path\" in a \"record_stop\" request"},
    };
    expect_refused(refusals);
}

TEST(DaemonControlProtocol, ASceneLoadNamesAnAbsolutePath) {
    const Request load{.kind = RequestKind::scene_load, .id = "s", .path = "/etc/hapticd/w.toml"};
    const std::string line = request_line(load);
    const ParsedRequest parsed = parse_request(line.substr(0, line.size() - 1));
    ASSERT_TRUE(parsed.request.has_value()) << parsed.error;
    EXPECT_EQ(parsed.request->kind, RequestKind::scene_load);
    EXPECT_EQ(parsed.request->path, "/etc/hapticd/w.toml");
    EXPECT_EQ(parsed.request->id, "s");
    const std::string too_long = "/" + std::string(kMaxRequestPathBytes, 'a');
    const Refusal refusals[] = {
        {R"({"v":1,"request":"scene_load"})",
         "\"path\" is missing: scene_load names the scene file to render"},
        {R"({"v":1,"request":"scene_load","path":["/a"]})",
         "\"path\" = [\"/a\"]: must be a string"},
        {R"({"v":1,"request":"scene_load","path":"scenes/w.toml"})",
         "\"path\" = \"scenes/w.toml\": an absolute path of at most 4095 bytes is needed"},
        {R"({"v":1,"request":"scene_load","path":")" + too_long + R"("})", "an absolute path"},
        {R"({"v":1,"request":"scene_load","path":"/w.toml","rate_hz":1})",
         "unknown field \"rate_hz\" in a \"scene_load\" request: it takes only v, id, request, "
         "path"},
    };
    expect_refused(refusals);
}

// identify's log is optional (the daemon names one beside its files); when given it is a name
// or an absolute path, as a recording's.
TEST(DaemonControlProtocol, AnIdentifyMayNameItsLog) {
    const ParsedRequest bare = parse_request(R"({"v":1,"request":"identify"})");
    ASSERT_TRUE(bare.request.has_value()) << bare.error;
    EXPECT_EQ(bare.request->kind, RequestKind::identify);
    EXPECT_FALSE(bare.request->path.has_value());
    const Request named{.kind = RequestKind::identify, .id = 4, .path = "/var/log/pen.csv"};
    const std::string line = request_line(named);
    const ParsedRequest parsed = parse_request(line.substr(0, line.size() - 1));
    ASSERT_TRUE(parsed.request.has_value()) << parsed.error;
    EXPECT_EQ(parsed.request->kind, RequestKind::identify);
    EXPECT_EQ(parsed.request->path, "/var/log/pen.csv");
    const std::string too_long = "/" + std::string(kMaxRequestPathBytes, 'a');
    const Refusal refusals[] = {
        {R"({"v":1,"request":"identify","path":true})", "\"path\" = true: must be a string"},
        {R"({"v":1,"request":"identify","path":""})", "a file name, or an absolute path"},
        {R"({"v":1,"request":"identify","path":")" + too_long + R"("})", "a file name, or"},
        {R"({"v":1,"request":"identify","periods":2})",
         "unknown field \"periods\" in a \"identify\" request: it takes only v, id, request, "
         "path"},
    };
    expect_refused(refusals);
}

TEST(DaemonControlProtocol, ARefusalKeepsTheRequestsId) {
    const ParsedRequest parsed = parse_request(R"({"v":1,"id":9,"request":"launch"})");
    EXPECT_FALSE(parsed.request.has_value());
    EXPECT_EQ(parsed.id, 9);
    const nlohmann::json reply = nlohmann::json::parse(error_reply(parsed.id, parsed.error));
    EXPECT_EQ(reply["id"], 9);
    EXPECT_EQ(reply["ok"], false);
    EXPECT_EQ(reply["v"], kProtocolVersion);
    EXPECT_EQ(reply["error"], parsed.error);
}

TEST(DaemonControlProtocol, ALongBadValueIsCutShortInTheMessage) {
    const std::string name(5000, 'x');
    const ParsedRequest parsed = parse_request(R"({"v":1,"request":")" + name + "\"}");
    ASSERT_FALSE(parsed.request.has_value());
    EXPECT_LT(parsed.error.size(), 200u) << parsed.error;
    EXPECT_NE(parsed.error.find("xxx..."), std::string::npos) << parsed.error;
}

TEST(DaemonControlProtocol, RepliesAreOneLineWithVersionIdAndOk) {
    const std::string ok = ok_reply("q", {{"state_before", "disabled"}});
    EXPECT_EQ(ok.find('\n'), ok.size() - 1);
    const nlohmann::json j = nlohmann::json::parse(ok);
    EXPECT_EQ(j["v"], 1);
    EXPECT_EQ(j["id"], "q");
    EXPECT_EQ(j["ok"], true);
    EXPECT_EQ(j["state_before"], "disabled");
    // An error's text with a newline in it still makes one line.
    const std::string error = error_reply(nullptr, "two\nlines");
    EXPECT_EQ(error.find('\n'), error.size() - 1);
}

/// A device that reports fixed link counts and nothing else.
class CountingDevice final : public device::Device {
  public:
    explicit CountingDevice(const device::LinkQuality& quality) : quality_(quality) {}
    void open(const device::DeviceConfig& /*config*/) override {}
    device::DeviceInfo info() const override { return {}; }
    servo::IoResult read(servo::Sample& /*sample*/) noexcept override {
        return servo::IoResult::ok;
    }
    servo::IoResult write(const servo::Command& /*command*/) noexcept override {
        return servo::IoResult::ok;
    }
    void close() noexcept override {}
    device::LinkQuality link_quality() const noexcept override { return quality_; }

  private:
    device::LinkQuality quality_;
};

TEST(DaemonControlStatus, LinkCarriesTheLoopsAndTheDevicesCounts) {
    servo::StatusSnapshot s;
    s.read_timeouts = 7;
    s.link_recoveries = 2;
    const device::LinkQuality q{.counted = true,
                                .frames_sent = 1000,
                                .frames_received = 990,
                                .bad_frames = 3,
                                .transfer_errors = 4,
                                .reply_timeouts = 7,
                                .missed_samples = 5,
                                .late = 6,
                                .duplicate = 8,
                                .device_errors = 9,
                                .disconnects = 1,
                                .reconnects = 1,
                                .wrong_session = 10,
                                .unexpected = 11,
                                .out_of_step = 12};
    const CountingDevice device(q);
    RunFacts facts;
    facts.link_source = &device;
    const nlohmann::json link = status_body(s, facts).at("link");
    EXPECT_EQ(link, nlohmann::json::parse(R"({"read_timeouts": 7, "link_recoveries": 2,
        "counted": true, "frames_sent": 1000, "frames_received": 990, "bad_frames": 3,
        "transfer_errors": 4, "reply_timeouts": 7, "missed_samples": 5, "late": 6,
        "duplicate": 8, "device_errors": 9, "disconnects": 1, "reconnects": 1,
        "wrong_session": 10, "unexpected": 11, "out_of_step": 12})"))
        << link.dump();
}

TEST(DaemonControlStatus, ADeviceWithoutCountsSaysSo) {
    servo::StatusSnapshot s;
    s.read_timeouts = 3;
    RunFacts facts;  // no device
    nlohmann::json link = status_body(s, facts).at("link");
    EXPECT_EQ(link.at("read_timeouts"), 3);
    EXPECT_EQ(link.at("counted"), false);
    EXPECT_EQ(link.at("bad_frames"), 0);
    const CountingDevice device(device::LinkQuality{});  // the default: counted = false
    facts.link_source = &device;
    link = status_body(s, facts).at("link");
    EXPECT_EQ(link.at("counted"), false);
    EXPECT_EQ(link.at("reply_timeouts"), 0);
    EXPECT_EQ(link.size(), 17u);
}

TEST(DaemonControlStatus, AnExternalWorldSaysWhereItStandsAndWhyThereIsNoForce) {
    servo::StatusSnapshot s;
    RunFacts facts;
    EXPECT_TRUE(status_body(s, facts).at("external_world").is_null());  // hapticd's own scene
    s.environment = {.external = true,
                     .world_state = 2,
                     .update = 41,
                     .stale_episodes = 1,
                     .rejected_updates = 3,
                     .since_update_s = 0.25,
                     .energy_j = 0.5,
                     .energy_removed_j = 0.125};
    EXPECT_EQ(status_body(s, facts).at("external_world"), nlohmann::json::parse(R"({
        "state": "stale",
        "why": "no update from the world for 0.25 s: the tool holds, and its force ramps to zero",
        "update": 41, "since_update_s": 0.25, "stale_episodes": 1, "rejected_updates": 3,
        "energy_j": 0.5, "energy_removed_j": 0.125})"));
    s.environment.world_state = 1;
    EXPECT_EQ(status_body(s, facts).at("external_world").at("why"), "");
    s.environment.world_state = 0;
    EXPECT_EQ(status_body(s, facts).at("external_world").at("state"), "waiting");
}

// A loop whose world failed: the status says why while the fault is latched.
class FailedWorldLoop final : public ServoControl {
  public:
    servo::StatusSnapshot status() const noexcept override { return snapshot; }
    servo::StatusSnapshot recent_status() const noexcept override { return snapshot; }
    std::string environment_failure() const override { return "evaluate() returned 7"; }
    void arm() noexcept override {}
    void disarm() noexcept override {}
    void reset() noexcept override {}
    std::uint64_t resets_requested() const noexcept override { return 0; }
    void set_coupling(const servo::CouplingGains&) noexcept override {}
    servo::CouplingGains coupling() const noexcept override { return {}; }
    void mark(std::uint32_t) noexcept override {}
    servo::StatusSnapshot snapshot{};
};

TEST(DaemonControlStatus, AWorldThatFailedSaysWhyWhileItsFaultIsLatched) {
    FailedWorldLoop loop;
    const RunFacts facts;
    const Request status{.kind = RequestKind::status, .id = 1};
    const Peer peer{.pid = 7, .uid = 1000, .gid = 1000};
    const auto failure = [&] {
        return nlohmann::json::parse(answer(status, peer, loop, facts).reply)
            .at("status")
            .at("environment_failure");
    };
    EXPECT_TRUE(failure().is_null());
    loop.snapshot.faults = servo::kFaultEnvironment;
    EXPECT_EQ(failure(), "evaluate() returned 7");
}

// A loop that keeps the gains it is given, for what a coupling request does.
class GainsLoop final : public ServoControl {
  public:
    servo::StatusSnapshot status() const noexcept override { return {}; }
    servo::StatusSnapshot recent_status() const noexcept override { return {}; }
    void arm() noexcept override {}
    void disarm() noexcept override {}
    void reset() noexcept override {}
    std::uint64_t resets_requested() const noexcept override { return 0; }
    void set_coupling(const servo::CouplingGains& gains) noexcept override {
        gains_ = gains;
        ++sets;
    }
    servo::CouplingGains coupling() const noexcept override { return gains_; }
    void mark(std::uint32_t number) noexcept override { marked = number; }
    int sets = 0;
    std::uint32_t marked = 0;

  private:
    servo::CouplingGains gains_{.stiffness_n_per_m = 2000.0, .damping_n_s_per_m = 0.5};
};

// The carried-out answer to a request: the worker's, when the request has one.
Answer carried_out(const Request& request, ServoControl& loop, const RunFacts& facts) {
    const Answer first = answer(request, Peer{.pid = 7, .uid = 1000, .gid = 1000}, loop, facts);
    return first.later ? first.later() : first;
}

// With [coupling] check = "off" every gains pass the check, but k_c = b_c = 0 is still
// refused: the daemon's servo config refuses it at the start ("a coupling of zero renders
// nothing"), so the socket must not set what a restart would refuse.
TEST(DaemonControlCoupling, ZeroGainsAreRefusedEvenWithTheCheckOff) {
    GainsLoop loop;
    RunFacts facts;
    facts.check_coupling = [](const servo::CouplingGains&) {
        return CouplingVerdict{.accepted = true, .verdict = "stability check OFF"};
    };
    const Answer zero = carried_out(Request{.kind = RequestKind::coupling,
                                            .id = 1,
                                            .stiffness_n_per_m = 0.0,
                                            .damping_n_s_per_m = 0.0},
                                    loop, facts);
    const nlohmann::json refused = nlohmann::json::parse(zero.reply);
    EXPECT_EQ(refused["ok"], false);
    EXPECT_NE(refused["error"].get<std::string>().find(
                  "coupling refused: stiffness and damping are both 0"),
              std::string::npos)
        << zero.reply;
    EXPECT_EQ(loop.sets, 0);
    EXPECT_EQ(loop.coupling().stiffness_n_per_m, 2000.0);

    // Either gain alone renders something, and passes.
    for (const auto& [k, b] : {std::pair{0.0, 0.5}, std::pair{100.0, 0.0}}) {
        const Answer one = carried_out(Request{.kind = RequestKind::coupling,
                                               .id = 2,
                                               .stiffness_n_per_m = k,
                                               .damping_n_s_per_m = b},
                                       loop, facts);
        EXPECT_EQ(nlohmann::json::parse(one.reply)["ok"], true) << one.reply;
        EXPECT_EQ(loop.coupling().stiffness_n_per_m, k);
        EXPECT_EQ(loop.coupling().damping_n_s_per_m, b);
    }
    EXPECT_EQ(loop.sets, 2);
}

}  // namespace
}  // namespace hapticd::daemon::control_socket
