// libFuzzer target for the reference device (DeviceEmulator, docs/protocol.md sections 5, 7):
// whatever a host sends, the device must answer only with well-formed device-to-host frames
// and never output force it should not.
//
// Input: byte 0 picks the mode.
//   even  raw: the rest is a serial byte stream, fed to handle_stream() in chunks;
//   odd   structured: after a valid hello (offering 1..1, or 1..2 when byte 0 has bit 1 set),
//         a list of operations, so that the fuzzer reaches deep states without having to
//         forge CRCs:
//           0x00-0x3F  advance_period() 1..4 times
//           0x40-0x7F  arm one fault knob (op & 15)
//           0x80-0xFF  a frame: type byte, payload size byte, payload bytes; the current
//                      session when op bit 0 is set (else 4 session bytes follow), the
//                      session's version unless op bit 1 is set (then a version byte
//                      follows); a good CRC.
// Invariants after every step: each reply decodes and goes device to host (unless a knob
// corrupted it on purpose), in the session's version; a version-2 sample names only a
// command it has received; |force| <= the limit; zero force without a session or with a
// latched fault.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>

#include "fuzz_check.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/device_emulator.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/protocol/wire.hpp"

namespace {

using namespace hapticd::device::protocol;

constexpr std::uint32_t kSession = 0x12345678u;

EmulatorConfig make_config() {
    EmulatorConfig config;
    config.sim.axes = 2;
    config.sim.force_limit_n = 5.0;
    config.sim.initial_position_m = {0.01, -0.02, 0.0};
    return config;
}

class Reader {
  public:
    explicit Reader(std::span<const std::byte> bytes) : bytes_(bytes) {}
    bool done() const { return at_ >= bytes_.size(); }
    std::uint8_t u8() { return done() ? 0 : static_cast<std::uint8_t>(bytes_[at_++]); }

  private:
    std::span<const std::byte> bytes_;
    std::size_t at_ = 0;
};

/// Knobs that make a reply unreadable or foreign on purpose.
std::uint32_t corrupting(const EmulatorFaults& f) {
    return f.corrupt_crc + f.truncate + f.wrong_session;
}

void check_force(const DeviceEmulator& device) {
    const auto force = device.output_force_n();
    const double limit_n = device.sim().config().force_limit_n;
    for (const double f : force) FUZZ_CHECK(std::isfinite(f) && std::abs(f) <= limit_n);
    if (!device.session_open() || device.latched_faults() != 0u || device.gone()) {
        for (const double f : force) FUZZ_CHECK(f == 0.0);
    }
    for (int i = 0; i < device.identity().axes; ++i) {
        FUZZ_CHECK(std::abs(device.sim().held_force_n()[i]) <= limit_n);
    }
}

void check_reply_frame(std::span<const std::byte> frame, bool may_be_corrupt,
                       const DeviceEmulator* device = nullptr) {
    Message message;
    const Error error = decode(frame, message);
    if (may_be_corrupt) return;
    FUZZ_CHECK(error == Error::none);
    FUZZ_CHECK(!is_host_to_device(type_of(message)));
    if (device == nullptr) return;
    if (const auto* sample = std::get_if<EncoderSample>(&message)) {
        FUZZ_CHECK(sample->version == device->version());
        // What it names arrived: a command no further back than the commands it applied.
        if (sample->names_applied()) {
            FUZZ_CHECK(sample->applied_lag < device->counters().commands_applied);
        }
    }
}

void handle_and_check(DeviceEmulator& device, std::span<const std::byte> frame) {
    const std::uint32_t knobs_before = corrupting(device.faults());
    const bool delayed_before = device.delayed_reply_pending();
    const bool unsent_before = device.faults().applied_unsent != 0u;  // names one on purpose
    std::array<std::byte, DeviceEmulator::kMaxReplySize> out{};
    const DeviceEmulator::Reply reply = device.handle(frame, out);
    FUZZ_CHECK(reply.frames <= DeviceEmulator::kMaxReplyFrames);
    // This step's knobs may have damaged its reply on purpose, and a reply held back by an
    // earlier step (which goes out first) may carry that step's damage.
    const bool may_be_corrupt = corrupting(device.faults()) != knobs_before || delayed_before;
    std::size_t offset = 0;
    for (std::size_t i = 0; i < reply.frames; ++i) {
        check_reply_frame(std::span<const std::byte>(out).subspan(offset, reply.frame_sizes[i]),
                          may_be_corrupt || unsent_before, &device);
        offset += reply.frame_sizes[i];
    }
    FUZZ_CHECK(offset == reply.size);
    check_force(device);
}

void run_raw(DeviceEmulator& device, std::span<const std::byte> bytes, std::size_t chunk) {
    std::array<std::byte, 8 * kMaxStreamFrameSize> out{};
    for (std::size_t at = 0; at < bytes.size(); at += chunk) {
        const std::size_t n = std::min(chunk, bytes.size() - at);
        const std::size_t written = device.handle_stream(bytes.subspan(at, n), out);
        FUZZ_CHECK(written <= out.size());
        StreamDecoder decoder;
        decoder.feed(std::span<const std::byte>(out).first(written),
                     [](std::span<const std::byte> frame) { check_reply_frame(frame, false); });
        FUZZ_CHECK(decoder.counters().overflows == 0 && decoder.counters().cobs_errors == 0);
        check_force(device);
    }
}

void arm_knob(EmulatorFaults& faults, std::uint8_t which) {
    switch (which & 15u) {
        case 0:
            faults.corrupt_crc = 1;
            break;
        case 1:
            faults.truncate = 1;
            break;
        case 2:
            faults.drop = 1;
            break;
        case 3:
            faults.wrong_session = 1;
            break;
        case 4:
            faults.sequence_gap = 3;
            break;
        case 5:
            faults.delay = 1;
            break;
        case 6:
            faults.stall = 2;
            break;
        case 8:
            faults.applied_unsent = 1;
            break;
        case 9:
            faults.clock_back_us = 1500;
            break;
        case 10:
            faults.applied_early_us = 700;
            break;
        default:
            faults.device_faults = kDeviceFaultOverTemperature;
            break;
    }
}

void run_structured(DeviceEmulator& device, Reader& in, std::uint8_t max_version) {
    Hello hello;
    hello.session = kSession;
    hello.max_version = max_version;
    std::array<std::byte, kMaxFrameSize> frame{};
    handle_and_check(device, std::span<const std::byte>(frame).first(encode(hello, frame).size));
    FUZZ_CHECK(device.session_open());
    while (!in.done()) {
        const std::uint8_t op = in.u8();
        if (op < 0x40) {
            for (int k = 0; k <= (op & 3); ++k) device.advance_period();
            check_force(device);
            continue;
        }
        if (op < 0x80) {
            arm_knob(device.faults(), op);
            continue;
        }
        const std::uint8_t type = in.u8();
        const std::size_t payload_size = in.u8() % (kMaxPayloadSize + 1);
        std::uint32_t session = device.session_open() ? device.session() : kSession;
        if ((op & 1u) == 0u) {
            session = 0;
            for (int i = 0; i < 4; ++i) session |= static_cast<std::uint32_t>(in.u8()) << (8 * i);
        }
        const std::uint8_t version = (op & 2u) != 0u ? in.u8() : device.version();
        frame.fill(std::byte{0});
        wire::store_u8(frame, kOffsetMagic, kMagic);
        wire::store_u8(frame, kOffsetVersion, version);
        wire::store_u8(frame, kOffsetType, type);
        wire::store_u8(frame, kOffsetPayloadSize, static_cast<std::uint8_t>(payload_size));
        wire::store_u32(frame, kOffsetSession, session);
        for (std::size_t i = 0; i < payload_size; ++i) {
            wire::store_u8(frame, kHeaderSize + i, in.u8());
        }
        const std::size_t crc_at = kHeaderSize + payload_size;
        wire::store_u32(frame, crc_at, crc32c(std::span<const std::byte>(frame).first(crc_at)));
        handle_and_check(device, std::span<const std::byte>(frame).first(crc_at + kCrcSize));
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static const EmulatorConfig config = make_config();
    DeviceEmulator device(config);
    const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
    const std::uint8_t mode = data[0];
    if ((mode & 1u) == 0u) {
        run_raw(device, bytes.subspan(1), 1 + (mode >> 1) % 16);
    } else {
        Reader in(bytes.subspan(1));
        run_structured(device, in, (mode & 2u) != 0u ? kProtocolVersion2 : kProtocolVersion1);
    }
    return 0;
}
