// The reference firmware's binary against docs/protocol.md, over its emulated serial line
// (hapticd-avr-sim, real-time clock): this test is the host, through the serial plugin's own
// link (SerialLink) and the host's protocol library. What the motor did is judged from the
// harness's pin record, in emulated time, so a slow or loaded host cannot change a verdict.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "emulated_hapkit.hpp"
#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "hapticd/device/serial/serial_link.hpp"
#include "scratch_dir.hpp"

namespace hapticd::testing {
namespace {

namespace protocol = device::protocol;
using device::link::LinkResult;
using Frame = std::vector<std::byte>;

constexpr std::uint32_t kSession = 0x600DF00Du;

/// The firmware's identity as firmware/config/hapkit.h builds it.
constexpr double kCountsPerMeterHapkit = 81572.06200906535;
constexpr std::int32_t kForceLimitUn = 5'000'000;

class Host {
  public:
    explicit Host(const std::string& port)
        : link_([&] {
              device::serial::SerialSettings settings;
              settings.port = port;
              return settings;
          }()) {
        link_.open();
    }

    template <typename M>
    void send(const M& message) {
        Frame frame(protocol::kMaxFrameSize);
        const protocol::Encoded encoded = protocol::encode(message, frame);
        ASSERT_TRUE(encoded.ok());
        frame.resize(encoded.size);
        send_raw(frame);
    }
    void send_raw(const Frame& frame) { ASSERT_EQ(link_.send(frame), LinkResult::ok); }

    /// The next reply within `timeout_ms` of wall time, decoded; nullopt if none came. The
    /// default is long: a loaded host may hold the emulation back, never the reverse.
    std::optional<protocol::Message> receive(int timeout_ms = 2000) {
        std::array<std::byte, protocol::kMaxFrameSize> frame{};
        std::size_t size = 0;
        const std::int64_t deadline = device::link::monotonic_now_ns() + timeout_ms * 1'000'000LL;
        if (link_.receive(frame, size, deadline) != LinkResult::ok) return std::nullopt;
        protocol::Message message;
        EXPECT_EQ(protocol::decode(std::span<const std::byte>(frame).first(size), message),
                  protocol::Error::none);
        return message;
    }

    template <typename M>
    M expect() {
        const auto reply = receive();
        EXPECT_TRUE(reply.has_value()) << "no reply";
        if (!reply) return M{};
        const M* m = std::get_if<M>(&*reply);
        EXPECT_NE(m, nullptr) << "reply type " << reply->index();
        return m != nullptr ? *m : M{};
    }

    protocol::Identity hello(std::uint32_t session = kSession) {
        send(protocol::Hello{.session = session, .min_version = 1, .max_version = 2});
        return expect<protocol::Identity>();
    }

    protocol::ForceCommand command(std::uint32_t sequence, double force_n, bool enable = true) {
        protocol::ForceCommand c;
        c.session = kSession;
        c.version = 2;
        c.sequence = sequence;
        c.flags = enable ? protocol::kCommandEnable : 0;
        c.axes = 1;
        c.force_un[0] = static_cast<std::int32_t>(std::lround(force_n * 1e6));
        return c;
    }

  private:
    device::serial::SerialLink link_;
};

/// The emulated times at which the motor's duty changed from or to zero.
struct DutyEdges {
    std::vector<double> on_s, off_s;
};

DutyEdges duty_edges(const PinRecord& pins) {
    DutyEdges edges;
    const auto& t = pins["time_s"];
    const auto& duty = pins["duty"];
    for (std::size_t i = 1; i < pins.rows(); ++i) {
        if (duty[i - 1] == 0.0 && duty[i] > 0.0) edges.on_s.push_back(t[i]);
        if (duty[i - 1] > 0.0 && duty[i] == 0.0) edges.off_s.push_back(t[i]);
    }
    return edges;
}

TEST(FilProtocol, TheFirmwareIntroducesItselfAsItsConfigSays) {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {});
    Host host(board.port());
    const protocol::Identity identity = host.hello();
    EXPECT_EQ(identity.version, 2);
    EXPECT_EQ(identity.session, kSession);
    EXPECT_EQ(identity.axes, 1);
    EXPECT_EQ(identity.force_limit_un, kForceLimitUn);
    // The float the AVR computes from the radii, exactly as a double.
    EXPECT_EQ(identity.counts_per_meter,
              static_cast<double>(static_cast<float>(kCountsPerMeterHapkit)));
    EXPECT_EQ(identity.period_us, 1000u);
    EXPECT_EQ(identity.watchdog_timeout_us, 20'000u);
    EXPECT_EQ(identity.serial_number(), "HAPKIT3-0001");
    // A version-1 host gets a version-1 session.
    host.send(protocol::Hello{.session = kSession + 1, .min_version = 1, .max_version = 1});
    EXPECT_EQ(host.expect<protocol::Identity>().version, 1);
    // Before any hello of its own, another host's frames are refused, and nothing moves.
    host.send(host.command(1, 1.0));
    const auto refused = host.expect<protocol::ErrorReport>();
    EXPECT_EQ(refused.code, protocol::ErrorCode::wrong_session);
    board.stop();
    EXPECT_TRUE(duty_edges(board.pins()).on_s.empty());
}

TEST(FilProtocol, TheWatchdogStopsTheMotorAtItsTimeout) {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {});
    Host host(board.port());
    host.hello();
    host.send(host.command(1, 2.0));
    const auto sample = host.expect<protocol::EncoderSample>();
    EXPECT_EQ(sample.command_sequence, 1u);
    EXPECT_NE(sample.status & protocol::kSampleForceActive, 0u);
    // The host goes quiet. The harness's record says when the motor stopped, in emulated
    // time: 20 ms after the command arrived (it took effect within 0.1 ms of arriving), at the
    // latest at the firmware's next period boundary.
    const auto later = host.receive(100);
    EXPECT_FALSE(later.has_value()) << "the device spoke unasked";
    host.send(protocol::Poll{.session = kSession, .version = 2});
    const auto tripped = host.expect<protocol::EncoderSample>();
    EXPECT_EQ(tripped.faults, protocol::kDeviceFaultWatchdog);
    EXPECT_EQ(tripped.status & protocol::kSampleForceActive, 0u);
    board.stop();
    const DutyEdges edges = duty_edges(board.pins());
    ASSERT_EQ(edges.on_s.size(), 1u);
    ASSERT_EQ(edges.off_s.size(), 1u);
    const double held_s = edges.off_s[0] - edges.on_s[0];
    EXPECT_GE(held_s, 0.020 - 1e-4);
    EXPECT_LE(held_s, 0.021 + 1e-4) << "more than a period past the timeout";
}

TEST(FilProtocol, DamagedAndForeignFramesNeverMoveTheMotor) {
    const ScratchDir dir;
    // Lockstep: how long the good command's force lasts before the bye is in emulated time,
    // whatever the host's round trip.
    EmulatedHapkit board(dir, {"--clock", "lockstep"});
    Host host(board.port());
    host.hello();
    Frame good(protocol::kMaxFrameSize);
    good.resize(protocol::encode(host.command(1, 3.0), good).size);
    Frame bad_crc = good;
    bad_crc.back() ^= std::byte{0x10};
    host.send_raw(bad_crc);
    EXPECT_FALSE(host.receive(20).has_value()) << "a frame with a bad CRC was answered";
    host.send_raw(Frame(good.begin(), good.end() - 3));
    EXPECT_FALSE(host.receive(20).has_value()) << "a truncated frame was answered";
    protocol::ForceCommand stale = host.command(1, 3.0);
    stale.session = 0x0BADCAFE;
    host.send(stale);
    EXPECT_EQ(host.expect<protocol::ErrorReport>().code, protocol::ErrorCode::wrong_session);
    // Random frames of every length: any reply must be a well-formed refusal, never a sample.
    std::mt19937 random(29);
    for (int i = 0; i < 40; ++i) {
        Frame garbage(1 + random() % protocol::kMaxFrameSize);
        for (auto& b : garbage) b = static_cast<std::byte>(random());
        host.send_raw(garbage);
        if (const auto reply = host.receive(5)) {
            EXPECT_TRUE(std::holds_alternative<protocol::ErrorReport>(*reply));
        }
    }
    protocol::ForceCommand wrong_axes = host.command(1, 3.0);
    wrong_axes.axes = 2;
    wrong_axes.force_un[1] = 1;
    host.send(wrong_axes);
    EXPECT_EQ(host.expect<protocol::ErrorReport>().code, protocol::ErrorCode::wrong_axes);
    // Then a good command moves it, and a bye stops it.
    host.send(host.command(1, 3.0));
    EXPECT_NE(host.expect<protocol::EncoderSample>().status & protocol::kSampleForceActive, 0u);
    host.send(protocol::Bye{.session = kSession, .version = 2});
    host.expect<protocol::ByeAck>();
    board.stop();
    const DutyEdges edges = duty_edges(board.pins());
    ASSERT_EQ(edges.on_s.size(), 1u) << "only the good command moved the motor";
    ASSERT_EQ(edges.off_s.size(), 1u);
    EXPECT_LT(edges.off_s[0] - edges.on_s[0], 0.0015) << "the bye did not stop it at once";
}

TEST(FilProtocol, ForceIsClampedToTheLimitAndTheDutyFollowsTheKinematics) {
    const ScratchDir dir;
    EmulatedHapkit board(dir, {"--record-interval", "1e-5"});
    Host host(board.port());
    host.hello();
    host.send(host.command(1, 2.0));
    EXPECT_EQ(host.expect<protocol::EncoderSample>().status & protocol::kSampleForceClamped, 0u);
    host.send(host.command(2, -9.0));
    EXPECT_NE(host.expect<protocol::EncoderSample>().status & protocol::kSampleForceClamped, 0u);
    host.send(host.command(3, 0.0, false));
    host.expect<protocol::EncoderSample>();
    board.stop();
    // The motor's force, from the pins through the paddle's kinematics: +2 N, then -5 N (the
    // limit), within one duty step (7.98 N / 256), and never the old duty the new way round
    // (motor_set() turns the motor off before it reverses).
    const PinRecord pins = board.pins();
    double most = 0.0, least = 0.0;
    for (const double f : pins["motor_force_n"]) {
        most = std::max(most, f);
        least = std::min(least, f);
    }
    const double step_n = 7.975088923626061 / 256;
    EXPECT_NEAR(most, 2.0, step_n);
    EXPECT_NEAR(least, -5.0, step_n);
    EXPECT_EQ(pins["motor_force_n"].back(), 0.0);
}

}  // namespace
}  // namespace hapticd::testing
