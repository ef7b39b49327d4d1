// Link diagnostics (`haptic-tune diag --config FILE`, docs/link-diagnostics.md): runs the
// configured device at zero force for a while and measures the link the servo will depend on.
//
// Every period (absolute deadlines at [servo] rate_hz): write a disabled zero-force command,
// then read its answer. The time from the write to the read's return is one round trip. It
// works through the Device interface only, so it measures any plugin (usb, hid, serial, and
// sim as a baseline) exactly as the daemon's loop drives it:
//   - round-trip time: percentiles and a histogram;
//   - no reply: reads that ended without a sample (timeout or dropped);
//   - late: samples flagged kStatusLate (a reply, or the device's command, came after its
//     period; the host discarded the stale reply);
//   - lost: no-reply reads that no late reply explains (a protocol device flags the sample
//     after a reply that missed its deadline; the exchange before it was late, not lost);
//   - sequence gaps: samples the device produced that never reached the host;
//   - clock drift: the least-squares slope of the device's timestamps against the host's
//     monotonic clock, in ppm, with the residual jitter.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "hapticd/daemon/config.hpp"

namespace hapticd::daemon {

struct DiagOptions {
    double duration_s = 5.0;  ///< (0, 3600]
    bool lockstep = false;    ///< virtual time (tests only: RTT and drift are then meaningless)
};

struct RttBin {
    double lo_us = 0.0;
    double hi_us = 0.0;  ///< +inf for the last bin
    std::uint64_t count = 0;
};

struct DiagReport {
    std::string plugin;
    std::string serial;
    int axes = 1;
    double rate_hz = 0.0;
    double duration_s = 0.0;  ///< measured, host clock
    std::uint64_t exchanges = 0;
    std::uint64_t replies = 0;
    double rtt_p50_us = 0.0, rtt_p90_us = 0.0, rtt_p99_us = 0.0, rtt_p999_us = 0.0;
    double rtt_max_us = 0.0, rtt_mean_us = 0.0;
    std::vector<RttBin> rtt_histogram;
    std::uint64_t no_reply = 0;
    std::uint64_t late = 0;
    std::uint64_t lost = 0;
    std::uint64_t sequence_gaps = 0;
    std::uint64_t disconnects = 0;  ///< reads or writes that found the device gone
    std::uint64_t errors = 0;       ///< reads or writes that failed otherwise
    std::uint64_t overruns = 0;     ///< periods the host itself missed (not the link's fault)
    double clock_drift_ppm = 0.0;
    double clock_jitter_us = 0.0;  ///< RMS residual of the device clock against the fit
    bool clock_fit = false;        ///< enough samples for a drift estimate
};

/// Opens config's device, runs the diagnosis, closes it (zero force). Throws
/// std::runtime_error on a device that cannot be opened. `log` gets progress messages.
DiagReport run_link_diag(const Config& config, const DiagOptions& options, std::ostream& log);

/// Human-readable report with a text histogram and a verdict on each figure.
std::string diag_text(const DiagReport& report);
/// The same as JSON (one object).
std::string diag_json(const DiagReport& report);

}  // namespace hapticd::daemon
