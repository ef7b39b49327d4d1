// libFuzzer target for the reference firmware's portable core (firmware/core/: the device side
// of docs/protocol.md in C, what runs on the ATmega328P): whatever a host sends, the firmware
// answers only with frames the host's own decoder accepts as device-to-host, and never puts
// out force it should not. The same input layout as protocol_device_fuzz.cpp (the C++
// reference device), so that their corpora seed each other.
//
// Input: byte 0 picks the mode.
//   even  raw: the rest is a serial byte stream, through the firmware's own COBS receiver
//         (hfw_cobs_push), a frame at a time into hfw_device_receive(); a period of the
//         board's clock passes between frames;
//   odd   structured: after a valid hello (offering 1..1, 1..2 when bit 1 of byte 0 is set,
//         1..3 when bit 2 is too), a list of operations:
//           0x00-0x3F  1..4 periods pass (the watchdog looked at each)
//           0x40-0x7F  the board's fault causes become op's bits 0, 4 and 7 (watchdog-free:
//                      encoder, internal), or none
//           0x80-0xFF  a frame: type byte, payload size byte, payload bytes; the current
//                      session when op bit 0 is set (else 4 session bytes follow), the
//                      session's version unless op bit 1 is set (then a version byte
//                      follows); a good CRC.
// Invariants after every step: each reply decodes with the host's decoder and goes device to
// host, a sample in the session's version naming only a command the session sent; every
// force the core sets is within the limit; zero force without a session or with a latched
// fault.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "fuzz_check.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/messages.hpp"
#include "hapticd/device/protocol/wire.hpp"

extern "C" {
#include "hfw_cobs.h"
#include "hfw_device.h"
}

namespace {

namespace proto = hapticd::device::protocol;

constexpr std::uint32_t kSession = 0x12345678u;
constexpr std::uint32_t kPeriodUs = 1000;
constexpr std::int32_t kForceLimitUn = 5'000'000;

struct Board {
    std::uint64_t now_us = 0;
    std::array<std::int32_t, HFW_MAX_AXES> force_un{};
    const hfw_device* device = nullptr;
};

void set_force(void* context, const std::int32_t force_un[HFW_MAX_AXES]) {
    auto* board = static_cast<Board*>(context);
    for (std::size_t i = 0; i < HFW_MAX_AXES; ++i) {
        FUZZ_CHECK(force_un[i] >= -kForceLimitUn && force_un[i] <= kForceLimitUn);
        board->force_un[i] = force_un[i];
    }
}

std::uint64_t now_us(void* context) { return static_cast<Board*>(context)->now_us; }

hfw_device_config make_config(std::uint8_t max_version) {
    hfw_device_config c{};
    c.axes = 2;
    c.max_version = max_version;
    c.paced = 1;
    c.force_limit_un = kForceLimitUn;
    c.counts_per_meter_bits = hfw_f64_bits(81572.0f);
    c.period_us = kPeriodUs;
    c.default_watchdog_timeout_us = 20'000;
    c.firmware_version = 0x00010000u;
    const char serial[] = "FUZZ-0001";
    std::copy(serial, serial + sizeof serial - 1, c.serial);
    return c;
}

/// What the host knows of the session it speaks: the commands it sent.
struct Session {
    std::uint64_t commands = 0;
};

void check_force(const hfw_device& d, const Board& board) {
    if (!d.session_open || d.latched_faults != 0u) {
        for (const std::int32_t f : board.force_un) FUZZ_CHECK(f == 0);
    }
}

void check_reply(const hfw_device& d, std::span<const std::byte> frame) {
    proto::Message message;
    FUZZ_CHECK(proto::decode(frame, message) == proto::Error::none);
    FUZZ_CHECK(!proto::is_host_to_device(proto::type_of(message)));
    if (const auto* sample = std::get_if<proto::EncoderSample>(&message)) {
        FUZZ_CHECK(d.session_open != 0u);
        FUZZ_CHECK(sample->version == d.version);
        FUZZ_CHECK(sample->session == d.session);
        FUZZ_CHECK(sample->axes == d.config->axes);
    }
}

/// One whole received frame through the core, its reply (and sample) checked.
void receive(hfw_device& d, Board& board, const std::uint8_t* frame, std::size_t size) {
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> out{};
    std::size_t out_size = 0;
    const hfw_reply reply =
        hfw_device_receive(&d, frame, size, board.now_us, out.data(), &out_size);
    if (reply == HFW_REPLY_FRAME) {
        FUZZ_CHECK(out_size >= HFW_MIN_FRAME_SIZE && out_size <= HFW_MAX_FRAME_SIZE);
        check_reply(d, std::as_bytes(std::span(out).first(out_size)));
    } else if (reply == HFW_REPLY_SAMPLE) {
        const std::int64_t counts[HFW_MAX_AXES] = {12345, -678, 0};
        const std::size_t n = hfw_device_sample(&d, counts, board.now_us, 0, out.data());
        FUZZ_CHECK(n >= HFW_MIN_FRAME_SIZE && n <= HFW_MAX_FRAME_SIZE);
        check_reply(d, std::as_bytes(std::span(out).first(n)));
    }
    check_force(d, board);
}

void pass_periods(hfw_device& d, Board& board, int periods) {
    for (int k = 0; k < periods; ++k) {
        board.now_us += kPeriodUs;
        (void)hfw_device_check_watchdog(&d, board.now_us);
        check_force(d, board);
    }
}

void run_raw(hfw_device& d, Board& board, std::span<const std::uint8_t> bytes) {
    std::array<std::uint8_t, HFW_MAX_FRAME_SIZE> frame{};
    hfw_cobs_decoder cobs{};
    hfw_cobs_init(&cobs, frame.data());
    for (const std::uint8_t byte : bytes) {
        if (hfw_cobs_push(&cobs, byte) != 0) {
            FUZZ_CHECK(cobs.size <= HFW_MAX_FRAME_SIZE);
            receive(d, board, frame.data(), cobs.size);
            pass_periods(d, board, 1);
        }
    }
}

void run_structured(hfw_device& d, Board& board, std::span<const std::uint8_t> bytes,
                    std::uint8_t max_version) {
    std::size_t at = 0;
    const auto u8 = [&] { return at < bytes.size() ? bytes[at++] : std::uint8_t{0}; };
    std::array<std::byte, proto::kMaxFrameSize> frame{};
    const proto::Encoded hello = proto::encode(proto::Hello{kSession, 1, max_version}, frame);
    receive(d, board, reinterpret_cast<const std::uint8_t*>(frame.data()), hello.size);
    FUZZ_CHECK(d.session_open != 0u);
    while (at < bytes.size()) {
        const std::uint8_t op = u8();
        if (op < 0x40) {
            pass_periods(d, board, 1 + (op & 3));
            continue;
        }
        if (op < 0x80) {
            const std::uint16_t causes =
                static_cast<std::uint16_t>(((op & 1u) != 0u ? HFW_FAULT_ENCODER : 0u) |
                                           ((op & 2u) != 0u ? HFW_FAULT_INTERNAL : 0u));
            hfw_device_set_fault_causes(&d, causes);
            check_force(d, board);
            continue;
        }
        const std::uint8_t type = u8();
        const std::size_t payload_size = u8() % (proto::kMaxPayloadSize + 1);
        std::uint32_t session = d.session_open != 0u ? d.session : kSession;
        if ((op & 1u) == 0u) {
            session = 0;
            for (int i = 0; i < 4; ++i) session |= static_cast<std::uint32_t>(u8()) << (8 * i);
        }
        const std::uint8_t version = (op & 2u) != 0u ? u8() : d.version;
        frame.fill(std::byte{0});
        proto::wire::store_u8(frame, proto::kOffsetMagic, proto::kMagic);
        proto::wire::store_u8(frame, proto::kOffsetVersion, version);
        proto::wire::store_u8(frame, proto::kOffsetType, type);
        proto::wire::store_u8(frame, proto::kOffsetPayloadSize,
                              static_cast<std::uint8_t>(payload_size));
        proto::wire::store_u32(frame, proto::kOffsetSession, session);
        for (std::size_t i = 0; i < payload_size; ++i) {
            proto::wire::store_u8(frame, proto::kHeaderSize + i, u8());
        }
        const std::size_t crc_at = proto::kHeaderSize + payload_size;
        proto::wire::store_u32(frame, crc_at,
                               proto::crc32c(std::span<const std::byte>(frame).first(crc_at)));
        receive(d, board, reinterpret_cast<const std::uint8_t*>(frame.data()),
                crc_at + proto::kCrcSize);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::uint8_t mode = data[0];
    const std::uint8_t max_version = (mode & 4u) != 0u ? 3 : (mode & 2u) != 0u ? 2 : 1;
    static const hfw_device_config config = make_config(3);  // the firmware speaks 1..3
    Board board;
    hfw_device device{};
    hfw_device_init(&device, &config, hfw_board{&set_force, &now_us, &board});
    const std::span<const std::uint8_t> rest(data + 1, size - 1);
    if ((mode & 1u) == 0u) {
        run_raw(device, board, rest);
    } else {
        run_structured(device, board, rest, max_version);
    }
    return 0;
}
