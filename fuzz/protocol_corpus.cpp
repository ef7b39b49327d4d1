// Writes the seed corpus of protocol_decode_fuzz and prints the worked examples of
// docs/protocol.md section 8, both from the encoder (protocol_examples.hpp).
//
//   protocol_corpus --corpus DIR          write the decoder's seeds into DIR
//                                         (fuzz/corpus/protocol_decode)
//   protocol_corpus --check DIR           exit 1 unless every seed is in DIR, byte for byte
//   protocol_corpus --device-corpus DIR   the same for the device fuzzer
//   protocol_corpus --check-device DIR    (fuzz/corpus/protocol_device)
//   protocol_corpus --markdown            print section 8's generated part
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "protocol_examples.hpp"

namespace {

using namespace hapticd::device::protocol;
using examples::Example;

struct Seed {
    std::string file;
    std::vector<std::byte> bytes;
};

std::vector<std::byte> stream_of(const std::vector<std::byte>& frame) {
    std::vector<std::byte> out(stream_encoded_size(frame.size()));
    encode_stream(frame, out);
    return out;
}

/// Deterministic bytes (splitmix64), for garbage between frames.
std::vector<std::byte> garbage(std::size_t size, std::uint64_t seed) {
    std::vector<std::byte> out;
    for (std::size_t i = 0; i < size; ++i) {
        std::uint64_t z = (seed += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        out.push_back(static_cast<std::byte>((z ^ (z >> 31)) & 0xFFu));
    }
    return out;
}

std::vector<Seed> seeds() {
    std::vector<Seed> out;
    const std::vector<Example> frames = examples::frame_examples();
    for (const Example& e : frames) out.push_back({"frame_" + e.name, e.bytes});
    for (const Example& e : examples::transport_examples()) out.push_back({e.name, e.bytes});

    // Corrupt frames: one per frame-level error, from the 3-axis command.
    const std::vector<std::byte>& command = [&frames]() -> const std::vector<std::byte>& {
        for (const Example& e : frames) {
            if (e.name == "command_3axis") return e.bytes;
        }
        throw std::logic_error("no command_3axis example");
    }();
    std::vector<std::byte> bad_crc = command;
    bad_crc.back() ^= std::byte{0x80};
    out.push_back({"corrupt_bad_crc", bad_crc});
    out.push_back(
        {"corrupt_truncated",
         {command.begin(), command.begin() + static_cast<std::ptrdiff_t>(command.size() / 2)}});
    std::vector<std::byte> bad_magic = command;
    bad_magic[0] = std::byte{0x00};
    out.push_back({"corrupt_bad_magic", bad_magic});
    std::vector<std::byte> long_frame = command;
    long_frame.push_back(std::byte{0x00});
    out.push_back({"corrupt_trailing_byte", long_frame});
    std::vector<std::byte> bad_version = command;
    bad_version[1] = std::byte{0x02};
    out.push_back({"corrupt_bad_version", bad_version});

    // A serial session with garbage before, between and inside (a frame cut by a delimiter).
    std::vector<std::byte> session = garbage(23, 1);
    for (const Example& e : frames) {
        const std::vector<std::byte> s = stream_of(e.bytes);
        session.insert(session.end(), s.begin(), s.end());
    }
    const std::vector<std::byte> noise = garbage(40, 2);
    session.insert(session.end(), noise.begin(), noise.end());
    session.push_back(std::byte{0x00});
    const std::vector<std::byte> cut = stream_of(command);
    session.insert(session.end(), cut.begin(), cut.begin() + 10);
    session.push_back(std::byte{0x00});
    session.insert(session.end(), cut.begin(), cut.end());
    out.push_back({"stream_session_with_garbage", session});
    out.push_back({"stream_garbage_only", garbage(200, 3)});
    return out;
}

void append_u32(std::vector<std::byte>& out, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::byte>((value >> (8 * i)) & 0xFFu));
}

/// One structured operation of protocol_device_fuzz: a frame in the current session.
void append_frame_op(std::vector<std::byte>& out, MessageType type,
                     const std::vector<std::byte>& payload) {
    out.push_back(std::byte{0x81});
    out.push_back(static_cast<std::byte>(type));
    out.push_back(static_cast<std::byte>(payload.size()));
    out.insert(out.end(), payload.begin(), payload.end());
}

std::vector<std::byte> command_payload(std::uint32_t sequence, std::uint8_t flags, std::int32_t fx,
                                       std::int32_t fy) {
    std::vector<std::byte> p;
    append_u32(p, sequence);
    p.push_back(std::byte{flags});
    p.push_back(std::byte{2});  // the device fuzzer's emulator has 2 axes
    p.push_back(std::byte{0});
    p.push_back(std::byte{0});
    append_u32(p, static_cast<std::uint32_t>(fx));
    append_u32(p, static_cast<std::uint32_t>(fy));
    return p;
}

/// Seeds for protocol_device_fuzz (its input format is in protocol_device_fuzz.cpp).
std::vector<Seed> device_seeds() {
    std::vector<Seed> out;
    // A session: configure, poll, commands, a quiet spell that trips the watchdog, a clear,
    // more commands, bye.
    std::vector<std::byte> session{std::byte{0x01}};
    std::vector<std::byte> timeout;
    append_u32(timeout, 5000);
    append_frame_op(session, MessageType::configure, timeout);
    append_frame_op(session, MessageType::poll, {});
    for (std::uint32_t n = 1; n <= 5; ++n) {
        append_frame_op(session, MessageType::command,
                        command_payload(n, kCommandEnable, 1'000'000, -7'000'000));
    }
    for (int i = 0; i < 3; ++i) session.push_back(std::byte{0x03});  // 4 periods each
    append_frame_op(session, MessageType::command, command_payload(6, kCommandEnable, 1, 1));
    append_frame_op(session, MessageType::command, command_payload(7, kCommandClearFaults, 0, 0));
    append_frame_op(session, MessageType::command, command_payload(9, kCommandEnable, 5, 5));
    append_frame_op(session, MessageType::bye, {});
    append_frame_op(session, MessageType::command, command_payload(10, kCommandEnable, 5, 5));
    out.push_back({"structured_session", session});

    // Every knob once, each followed by a command.
    std::vector<std::byte> knobs{std::byte{0x01}};
    for (std::uint8_t k = 0; k < 8; ++k) {
        knobs.push_back(std::byte{static_cast<std::uint8_t>(0x40 + k)});
        append_frame_op(knobs, MessageType::command,
                        command_payload(k + 1u, kCommandEnable, 2'000'000, 0));
    }
    out.push_back({"structured_knobs", knobs});

    // Version 2: the session in 1..2, the acknowledgement knobs, commands after quiet spells.
    std::vector<std::byte> v2{std::byte{0x03}};
    append_frame_op(v2, MessageType::poll, {});
    for (std::uint32_t n = 1; n <= 4; ++n) {
        append_frame_op(v2, MessageType::command,
                        command_payload(n, kCommandEnable, 500'000, -500'000));
    }
    for (std::uint8_t k = 8; k <= 10; ++k) {
        v2.push_back(std::byte{static_cast<std::uint8_t>(0x40 + k)});
        append_frame_op(v2, MessageType::command,
                        command_payload(k - 3u, kCommandEnable, 1'000'000, 0));
    }
    v2.push_back(std::byte{0x01});  // two quiet periods
    append_frame_op(v2, MessageType::poll, {});
    v2.push_back(std::byte{0x83});  // a version-1 poll in the version-2 session
    v2.push_back(static_cast<std::byte>(MessageType::poll));
    v2.push_back(std::byte{0});
    v2.push_back(std::byte{1});
    append_frame_op(v2, MessageType::bye, {});
    out.push_back({"structured_version2", v2});

    // Refusals: a new hello, a wrong session, a device-to-host type, a bad version.
    std::vector<std::byte> refusals{std::byte{0x01}};
    std::vector<std::byte> hello_payload{std::byte{1}, std::byte{1}, std::byte{0}, std::byte{0}};
    refusals.push_back(std::byte{0x80});  // own session bytes follow
    refusals.push_back(static_cast<std::byte>(MessageType::hello));
    refusals.push_back(std::byte{4});
    append_u32(refusals, 0xCAFE0001u);
    refusals.insert(refusals.end(), hello_payload.begin(), hello_payload.end());
    refusals.push_back(std::byte{0x80});
    refusals.push_back(static_cast<std::byte>(MessageType::poll));
    refusals.push_back(std::byte{0});
    append_u32(refusals, 0x0BADCAFEu);
    append_frame_op(refusals, MessageType::sample, std::vector<std::byte>(40));
    refusals.push_back(std::byte{0x83});  // a version byte follows
    refusals.push_back(static_cast<std::byte>(MessageType::poll));
    refusals.push_back(std::byte{0});
    refusals.push_back(std::byte{2});
    out.push_back({"structured_refusals", refusals});

    // Raw serial: garbage, then hello and poll in COBS.
    std::vector<std::byte> raw{std::byte{0x06}};
    const std::vector<std::byte> noise = garbage(30, 4);
    raw.insert(raw.end(), noise.begin(), noise.end());
    raw.push_back(std::byte{0x00});
    for (const Example& e : examples::frame_examples()) {
        if (e.name != "hello" && e.name != "poll" && e.name != "configure") continue;
        const std::vector<std::byte> s = stream_of(e.bytes);
        raw.insert(raw.end(), s.begin(), s.end());
    }
    out.push_back({"raw_serial_handshake", raw});
    return out;
}

std::vector<std::byte> read_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::byte> bytes(chars.size());
    for (std::size_t i = 0; i < chars.size(); ++i) bytes[i] = static_cast<std::byte>(chars[i]);
    return bytes;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string mode = argc >= 2 ? argv[1] : "";
    if (mode == "--markdown" && argc == 2) {
        std::cout << examples::kMarkdownBegin << "\n\n"
                  << examples::markdown() << examples::kMarkdownEnd << "\n";
        return 0;
    }
    const bool write = mode == "--corpus" || mode == "--device-corpus";
    const bool check = mode == "--check" || mode == "--check-device";
    if ((write || check) && argc == 3) {
        const std::filesystem::path dir = argv[2];
        const bool device = mode == "--device-corpus" || mode == "--check-device";
        int stale = 0;
        for (const Seed& seed : device ? device_seeds() : seeds()) {
            const std::filesystem::path path = dir / (seed.file + ".bin");
            if (write) {
                std::filesystem::create_directories(dir);
                std::ofstream out(path, std::ios::binary);
                out.write(reinterpret_cast<const char*>(seed.bytes.data()),
                          static_cast<std::streamsize>(seed.bytes.size()));
            } else if (!std::filesystem::exists(path) || read_file(path) != seed.bytes) {
                std::cerr << "stale or missing seed: " << path.string() << "\n";
                ++stale;
            }
        }
        if (stale > 0) {
            std::cerr << "regenerate with: protocol_corpus "
                      << (device ? "--device-corpus " : "--corpus ") << dir.string() << "\n";
            return 1;
        }
        return 0;
    }
    std::cerr << "usage: protocol_corpus --corpus DIR | --check DIR | --device-corpus DIR |"
                 " --check-device DIR | --markdown\n";
    return 2;
}
