// The loop delay autotune sizes the gains for (docs/autotune.md): --delay; else, when it
// runs the device, the delay measured over the link at zero force before the
// identification run (tools/haptic-tune/link_diag.hpp, as `haptic-tune diag`), when the device
// reports when its commands take effect; else [device.model] delay. A device that cannot
// report it with no delay stated anywhere is refused (a guess of none would size gains past
// the limit of every real device). From --log there is no device: [device.model] delay,
// else none, with a warning.
#pragma once

#include <optional>
#include <string>

#include "hapticd/daemon/config.hpp"
#include "link_diag.hpp"

namespace hapticd::tools {

/// Where the loop delay came from.
enum class DelaySource { option, measured, config, none };

/// "--delay", "measured", "config", "none".
const char* to_string(DelaySource source);

/// How long the link is run at zero force to measure the delay: 2000 commands at 1 kHz, so
/// that the p99 rests on 20 of them.
inline constexpr double kDelayMeasurementS = 2.0;

struct LoopDelay {
    double delay_s = 0.0;  ///< what the gains are sized for
    /// What the identification shifts the logged forces by (IdentificationOptions::delay_s):
    /// the measured median when measured (the delay the run's forces met), else delay_s.
    double identification_delay_s = 0.0;
    DelaySource source = DelaySource::none;
    std::optional<daemon::DiagReport> measurement;  ///< when it ran the link
    std::string note;  ///< one line for the report: how the delay was found
};

/// --delay (delay_option), else the link's measurement (unless from_log), else the
/// config's [device.model] delay when the file states one
/// (daemon::DeviceModel::delay_stated). `lockstep`: the device keeps virtual time
/// with the host (diag --lockstep). Throws AutotuneError when the delay is unknown or the
/// device fails.
LoopDelay find_loop_delay(std::optional<double> delay_option, bool from_log,
                          const daemon::Config& config, bool lockstep);

/// "1.5 periods".
std::string periods_text(double delay_s, double rate_hz);

}  // namespace hapticd::tools
