// Helpers shared by the serial transport's tests: the emulated device they run against, the
// plugin table and link settings for a port, byte helpers.
#pragma once

#include <string>

#include "hapticd/device/protocol/device_emulator.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/serial/serial_settings.hpp"
#include "hapticd/servo/monotonic_clock.hpp"
#include "pen_display_emulator.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::testing {

using device::protocol::testing::Bytes;
using device::protocol::testing::bytes_of;
using device::protocol::testing::encoded;
using device::protocol::testing::hex;
using device::protocol::testing::Noise;

inline constexpr const char* kEmulatorSerial = "EMU-SERIAL-1";

/// The pen display of the HIL tests (pen_display_emulator.hpp) with `axes` axes, serial
/// kEmulatorSerial.
inline device::protocol::EmulatorConfig emulator_config(int axes = 1) {
    return pen_display_emulator(kEmulatorSerial, axes);
}

/// Link settings for `port` as make_serial_link() would make them, the defaults otherwise.
inline device::serial::SerialSettings settings_for(const std::string& port) {
    device::serial::SerialSettings s;
    s.port = port;
    s.source = "test.toml";
    return s;
}

/// COBS + delimiter, as on the line.
inline Bytes stream_encoded(const Bytes& frame) {
    Bytes out(device::protocol::stream_encoded_size(frame.size()));
    const auto result = device::protocol::encode_stream(frame, out);
    out.resize(result.ok() ? result.size : 0);
    return out;
}

inline std::int64_t now_ns() { return servo::monotonic_now_ns(); }

}  // namespace hapticd::testing
