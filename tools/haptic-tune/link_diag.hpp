// Link diagnostics (`haptic-tune diag --config FILE`, docs/link-diagnostics.md): runs the
// configured device at zero force for a while and measures the link the servo will depend on.
//
// Every period (absolute deadlines at [servo] rate_hz, or as the device answers when it paces
// the loop): write a disabled zero-force command, then read its answer. The time from the write to
// the read's return is one round trip. A device that takes its sample when read() is called (the
// sim: DeviceInfo::samples_at_read) is read first and then written, as the daemon's tick does, and
// its "round trip" is the two calls. It works through the Device interface only, so it measures any
// plugin (usb, hid, serial, and sim as a baseline) exactly as the daemon's loop drives it:
//   - round-trip time: percentiles and a histogram;
//   - no reply: reads that ended without a sample (timeout or dropped);
//   - late: samples flagged kStatusLate (a reply, or the device's command, came after its
//     period; the host discarded the stale reply);
//   - lost: no-reply reads that no late reply explains (a protocol device flags the sample
//     after a reply that missed its deadline; the exchange before it was late, not lost);
//   - sequence gaps: samples the device produced that never reached the host;
//   - clock drift: the least-squares slope of the device's timestamps against the host's
//     monotonic clock, in ppm, with the residual jitter;
//   - the loop delay D, when the device says when each command took effect (the open
//     protocol's version 2, the sim): for every command, the device time its force took
//     effect minus the device time of the sample it was computed from (the last one read
//     before it was written), both on the device's clock, so that no one-way latency needs
//     to be known. Split into the host's part (host clock: from the read() that returned the
//     sample to the write() of the command) and the rest (the link both ways and the
//     device). Bad acknowledgements (a command never sent, device times going backwards, a
//     force before its sample) are counted, never used. A device that does not say is
//     reported as such, with what is missing, and no number.
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

/// Nearest-rank percentiles of one figure, in seconds.
struct DelayStats {
    double p50 = 0.0, p99 = 0.0, max = 0.0;
};

/// The loop delay's value for [device.model] delay: the p99 rounded up to the next multiple
/// of this many periods (a conservative value that does not change with every run's jitter).
inline constexpr double kDelayRoundingPeriods = 0.05;

/// What the diagnosis concludes: the first figure that a 1 kHz-class servo cannot live with,
/// in the order the rules are checked (no reply; p99 round trip over 30 % of the period, for a
/// device that does not pace the loop;
/// over 0.1 % of exchanges lost or late; timestamps or acknowledgements that contradict
/// themselves; a configured delay below the measured p99), or ok.
struct DiagVerdict {
    enum class Level { ok, warn, fail };
    Level level = Level::ok;
    std::string text;  ///< "ok: the link keeps up with 1000 Hz", "WARN: ...", "FAIL: ..."
    bool ok() const noexcept { return level == Level::ok; }
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

    // The loop delay (encoder sample -> force in effect).
    bool lockstep = false;
    bool samples_at_read = false;  ///< DeviceInfo::samples_at_read
    /// The device paces the loop (DeviceInfo::paces_loop: protocol version 3's paced flag, or
    /// lockstep): no host deadlines; each round trip includes the wait for the device's period
    /// boundary, so it is not judged against the period.
    bool paced = false;
    int protocol_version = 0;          ///< 0: not an open-protocol device
    double configured_delay_s = 0.0;   ///< [device.model] delay
    bool delay_measured = false;       ///< at least one command's delay was measured
    std::string delay_missing;         ///< !delay_measured: why, naming what is missing
    std::uint64_t delay_commands = 0;  ///< commands whose delay was measured
    DelayStats delay_s;                ///< D, device clock
    DelayStats host_s;                 ///< read() of the sample -> write() of the command, host
    DelayStats link_s;                 ///< D - host, per command: the link and the device
    /// The split is physical: real time (not --lockstep) and no command's D below its host
    /// part (a device clock that stands still while the host holds the sample, such as the
    /// reference emulator's virtual one, gives D < host).
    bool delay_split = false;
    double recommended_delay_s = 0.0;  ///< p99 rounded up to kDelayRoundingPeriods
    // What the samples said about when commands took effect (servo::AppliedReport).
    std::uint64_t applied_unsupported = 0;  ///< samples with nothing to say
    std::uint64_t applied_none = 0;         ///< "no command in effect yet" and the like
    std::uint64_t bad_ack_command = 0;      ///< named a command never sent (or went back)
    std::uint64_t bad_ack_time = 0;         ///< the device's times contradicted themselves
    std::uint64_t clock_backwards = 0;      ///< a sample's device time before the previous one
    std::uint64_t acausal = 0;              ///< a force in effect before its sample was taken

    /// The share of exchanges, %.
    double percent_of_exchanges(std::uint64_t n) const noexcept;
    DiagVerdict verdict() const;
};

/// Opens config's device, runs the diagnosis, closes it (zero force). Throws
/// std::runtime_error on a device that cannot be opened. `log` gets progress messages.
DiagReport run_link_diag(const Config& config, const DiagOptions& options, std::ostream& log);

/// Human-readable report with a text histogram; its last line is "verdict: " and the
/// verdict's text.
std::string diag_text(const DiagReport& report);
/// The same as JSON (one object), with the verdict as {"ok", "text"}.
std::string diag_json(const DiagReport& report);

}  // namespace hapticd::daemon
