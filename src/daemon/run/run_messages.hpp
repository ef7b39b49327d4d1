// The daemon's own lines on its log stream (standard error, the journal): the device line,
// the live status line and the fault changes (docs/daemon.md "Messages").
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "hapticd/device/device.hpp"
#include "hapticd/env/environment.hpp"
#include "hapticd/servo/servo_loop.hpp"

namespace hapticd::daemon {

/// "hapticd: " and the [servo] name, if any ("hapticd: left arm: "): how the run's first
/// line begins, so that the journal of several instances tells them apart.
std::string start_line_prefix(const Config& config);
/// "sim device, 3 axes, lockstep clock": what the run's first line says of the device.
std::string device_line(const device::DeviceInfo& info);
/// "hapticd: t 1.00 s  x [..] mm  xe [..] mm  f [..] N  running  overruns 0  faults none"
/// (the state, servo_state.hpp; "arming 40%" during the soft start).
std::string status_line(const servo::StatusSnapshot& s, int axes);
/// "device_lost,overspeed": the latched faults' names.
std::string fault_names(std::uint32_t faults);
/// One line when the latched faults change (seen from the watcher: a change shorter than
/// its poll may go unlogged; the summary counts every one).
std::string fault_change_line(std::uint32_t before, const servo::StatusSnapshot& now,
                              const Config& config);
/// The STATUS= line systemd shows for the run (systemctl status): "running, 1000 Hz
/// (measured 999.9), tick 12000, overruns 0, faults none", then `note` (what real time
/// refused) when not empty. `measured_rate_hz` is the ticks of the last second of wall time,
/// 0 when the servo stalled; none leaves it out (the first second, or a lockstep run, whose
/// rate is the device's).
std::string service_status(const servo::StatusSnapshot& s, double rate_hz,
                           std::optional<double> measured_rate_hz, const std::string& note = {});
/// "hapticd: t 60.0 s: running, tick 60000, 1000.0 Hz over the last 60.0 s, overruns 0 (+0),
/// faults none": the run's figures since `before`, `seconds` earlier.
std::string figures_line(const servo::StatusSnapshot& now, const servo::StatusSnapshot& before,
                         double seconds);
/// What real time refused, once the servo thread has asked: a warning on `log` with the
/// brief report and how to grant each refusal (realtime_advice.hpp); returns the note for
/// STATUS= ("realtime refused: SCHED_FIFO"), empty when everything was granted.
std::string report_realtime(const servo::RealtimeRequest& request,
                            const servo::RealtimeReport& report, std::ostream& log);
/// "[1.00 -2.50]": the first `axes` components, in millimetres.
std::string millimetres(const env::Vec3& v, int axes);

}  // namespace hapticd::daemon
