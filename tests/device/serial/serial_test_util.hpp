// Helpers shared by the serial transport's tests: the emulated device they run against, the
// plugin table and link settings for a port, byte helpers.
#pragma once

#include <string>

#include "hapticd/device/protocol/device_emulator.hpp"
#include "hapticd/device/protocol/stream_framer.hpp"
#include "hapticd/device/serial/serial_settings.hpp"
#include "hapticd/servo/monotonic_clock.hpp"
#include "protocol_test_util.hpp"

namespace hapticd::testing {

using device::protocol::testing::Bytes;
using device::protocol::testing::bytes_of;
using device::protocol::testing::encoded;
using device::protocol::testing::hex;
using device::protocol::testing::Noise;

inline constexpr const char* kEmulatorSerial = "EMU-SERIAL-1";

/// A 1-axis device at 1 kHz: the pen display of the HIL tests (m = 0.1 kg, b = 2 N s/m,
/// 10 um encoder, 20 N).
inline device::protocol::EmulatorConfig emulator_config(int axes = 1) {
    device::protocol::EmulatorConfig c;
    c.sim.axes = axes;
    c.sim.rate_hz = 1000.0;
    c.sim.mass_kg = 0.1;
    c.sim.damping_n_s_per_m = 2.0;
    c.sim.counts_per_meter = 1e5;
    c.sim.force_limit_n = 20.0;
    c.serial_number = kEmulatorSerial;
    return c;
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
