// The pen display of pen_display.hpp as a protocol device: the reference device (the
// emulator) behind the usb, hid and serial transports' test rigs, with the HIL tests' numbers
// (m = 0.1 kg, b = 2 N s/m, 1 kHz, 1e5 counts/m, 20 N). The emulator's clock is lockstep.
#pragma once

#include <string>

#include "hapticd/device/protocol/device_emulator.hpp"
#include "pen_display.hpp"

namespace hapticd::testing {

/// The pen display with `axes` identical axes and the serial number `serial`.
inline device::protocol::EmulatorConfig pen_display_emulator(const std::string& serial = "EMU-0001",
                                                             int axes = 1) {
    device::protocol::EmulatorConfig config;
    config.sim.axes = axes;
    config.sim.rate_hz = kRateHz;
    config.sim.mass_kg = kPenMassKg;
    config.sim.damping_n_s_per_m = kPenDampingNsPerM;
    config.sim.counts_per_meter = kCountsPerMeter;
    config.sim.force_limit_n = kForceLimitN;
    config.sim.clock = device::sim::SimClock::lockstep;
    config.serial_number = serial;
    return config;
}

}  // namespace hapticd::testing
