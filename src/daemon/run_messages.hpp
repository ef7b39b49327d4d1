// The daemon's own lines on its log stream (standard error, the journal): the device line,
// the live status line and the fault changes (docs/daemon.md "Messages").
#pragma once

#include <cstdint>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/env/environment.hpp"
#include "hapticd/servo/servo_loop.hpp"

namespace hapticd::daemon {

/// "sim device, 3 axes, lockstep clock": what the run's first line says of the device.
std::string device_line(const device::DeviceInfo& info);
/// "hapticd: t 1.00 s  x [..] mm  xe [..] mm  f [..] N  armed  overruns 0  faults none".
std::string status_line(const servo::StatusSnapshot& s, int axes);
/// "device_lost,overspeed": the latched faults' names.
std::string fault_names(std::uint32_t faults);
/// One line when the latched faults change (seen from the watcher: a change shorter than
/// its poll may go unlogged; the summary counts every one).
std::string fault_change_line(std::uint32_t before, const servo::StatusSnapshot& now,
                              const Config& config);
/// The STATUS= line systemd shows for the run (systemctl status): "armed, 1000 Hz, tick
/// 12000, overruns 0, faults none".
std::string service_status(const servo::StatusSnapshot& s, double rate_hz);
/// "[1.00 -2.50]": the first `axes` components, in millimetres.
std::string millimetres(const env::Vec3& v, int axes);

}  // namespace hapticd::daemon
