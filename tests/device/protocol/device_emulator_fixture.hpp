// The reference device driven by a host that frames requests and reads replies: the fixture of
// device_emulator_test.cpp and device_emulator_faults_test.cpp.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "alloc_guard.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/device_emulator.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/device/protocol/servo_convert.hpp"
#include "hapticd/device/protocol/status_map.hpp"
#include "hapticd/device/protocol/transport.hpp"
#include "hapticd/device/protocol/wire.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::device::protocol::emulator_fixture {

using testing::Bytes;
using testing::encoded;
using testing::Noise;
using Verdict = ReplyTracker::Verdict;

inline constexpr std::uint32_t kSession = 0x600DF00Du;

inline EmulatorConfig config(int axes = 3) {
    EmulatorConfig c;
    c.sim.axes = axes;
    c.sim.rate_hz = 1000.0;
    c.sim.mass_kg = 0.2;
    c.sim.damping_n_s_per_m = 1.5;
    c.sim.counts_per_meter = 2e5;
    c.sim.force_limit_n = 10.0;
    c.serial_number = "EMU-TEST-1";
    return c;
}

/// What a host received for one request: each frame, decoded.
struct Received {
    Bytes bytes;
    Error error = Error::none;
    Message message;
};

/// A minimal host: sends frames to the emulator and decodes what comes back.
class Host {
  public:
    explicit Host(DeviceEmulator& device) : device_(device) {}

    std::vector<Received> send_bytes(std::span<const std::byte> frame) {
        std::array<std::byte, DeviceEmulator::kMaxReplySize> out{};
        const DeviceEmulator::Reply reply = device_.handle(frame, out);
        std::vector<Received> received;
        std::size_t offset = 0;
        for (std::size_t i = 0; i < reply.frames; ++i) {
            Received r;
            r.bytes.assign(
                out.begin() + static_cast<std::ptrdiff_t>(offset),
                out.begin() + static_cast<std::ptrdiff_t>(offset + reply.frame_sizes[i]));
            offset += reply.frame_sizes[i];
            r.error = decode(r.bytes, r.message);
            received.push_back(std::move(r));
        }
        EXPECT_EQ(offset, reply.size);
        return received;
    }

    template <typename M>
    std::vector<Received> send(const M& message) {
        const Bytes frame = encoded(message);
        EXPECT_FALSE(frame.empty());
        return send_bytes(frame);
    }

    /// Sends and expects exactly one well-formed reply of type R.
    template <typename R, typename M>
    R ask(const M& message) {
        const std::vector<Received> received = send(message);
        EXPECT_EQ(received.size(), 1u);
        if (received.size() != 1 || received[0].error != Error::none ||
            !std::holds_alternative<R>(received[0].message)) {
            ADD_FAILURE() << "expected one " << typeid(R).name();
            return R{};
        }
        return std::get<R>(received[0].message);
    }

    /// Opens a session offering versions 1..max_version; later frames use the chosen one.
    Identity hello(std::uint32_t session = kSession, std::uint8_t max_version = kProtocolVersion1) {
        Hello hello;
        hello.session = session;
        hello.max_version = max_version;
        session_ = session;
        const Identity identity = ask<Identity>(hello);
        version_ = identity.version;
        tracker_.start(session, version_);
        return identity;
    }

    ForceCommand command_frame(const std::array<double, 3>& force_n, bool enable = true,
                               std::uint8_t extra_flags = 0) {
        servo::Command command;
        command.enable = enable;
        command.force_n = force_n;
        ForceCommand frame;
        EXPECT_TRUE(make_force_command(command, device_.identity().axes, session_, next_sequence_++,
                                       frame));
        frame.flags |= extra_flags;
        frame.version = version_;
        return frame;
    }

    EncoderSample command(const std::array<double, 3>& force_n, bool enable = true,
                          std::uint8_t extra_flags = 0) {
        const ForceCommand frame = command_frame(force_n, enable, extra_flags);
        tracker_.command_sent(frame.sequence);
        return ask<EncoderSample>(frame);
    }

    EncoderSample poll() {
        Poll poll;
        poll.session = session_;
        poll.version = version_;
        return ask<EncoderSample>(poll);
    }

    ReplyTracker& tracker() { return tracker_; }
    std::uint32_t session() const { return session_; }
    std::uint32_t& next_sequence() { return next_sequence_; }

  private:
    DeviceEmulator& device_;
    std::uint32_t session_ = 0;
    std::uint8_t version_ = kProtocolVersion1;
    std::uint32_t next_sequence_ = 1;
    ReplyTracker tracker_;
};

inline ErrorReport expect_error(const std::vector<Received>& received, ErrorCode code) {
    EXPECT_EQ(received.size(), 1u);
    if (received.size() != 1 || received[0].error != Error::none ||
        !std::holds_alternative<ErrorReport>(received[0].message)) {
        ADD_FAILURE() << "expected an error message " << to_string(code);
        return {};
    }
    const auto& report = std::get<ErrorReport>(received[0].message);
    EXPECT_EQ(report.code, code) << to_string(report.code);
    return report;
}

// ---- handshake ----

}  // namespace hapticd::device::protocol::emulator_fixture
