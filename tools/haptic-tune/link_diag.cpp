// Link diagnostics: the device at zero force, one exchange per period (link_diag.hpp).
#include "link_diag.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "hapticd/daemon/device_open.hpp"
#include "hapticd/input/range.hpp"
#include "hapticd/servo/monotonic_clock.hpp"
#include "hapticd/servo/nearest_rank.hpp"
#include "hapticd/tune/input_checks.hpp"

namespace hapticd::daemon {
namespace {

using servo::IoResult;

constexpr double kInf = std::numeric_limits<double>::infinity();
/// How long a diagnosis may run (DiagOptions::duration_s).
constexpr input::Range kDiagDuration{.lo = 0.0, .hi = 3600.0, .lo_open = true, .unit = "s"};
/// Histogram edges, us: fine below a millisecond, where a 1 kHz loop lives.
constexpr double kEdgesUs[] = {0, 25, 50, 100, 200, 300, 500, 750, 1000, 2000, 5000, 10000, kInf};

/// Least squares of device time against host time: slope - 1 in ppm and the RMS residual.
void fit_clock(const std::vector<double>& host_s, const std::vector<double>& device_s,
               DiagReport& report) {
    const std::size_t n = host_s.size();
    if (n < 10) return;
    double mean_h = 0.0, mean_d = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        mean_h += host_s[i];
        mean_d += device_s[i];
    }
    mean_h /= static_cast<double>(n);
    mean_d /= static_cast<double>(n);
    double shh = 0.0, shd = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        shh += (host_s[i] - mean_h) * (host_s[i] - mean_h);
        shd += (host_s[i] - mean_h) * (device_s[i] - mean_d);
    }
    if (shh <= 0.0) return;
    const double slope = shd / shh;
    double sse = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double r = device_s[i] - mean_d - slope * (host_s[i] - mean_h);
        sse += r * r;
    }
    report.clock_drift_ppm = (slope - 1.0) * 1e6;
    report.clock_jitter_us = std::sqrt(sse / static_cast<double>(n)) * 1e6;
    report.clock_fit = true;
}

/// The sample a command is computed from.
struct Basis {
    bool sound = false;            ///< a sample, with a device time not behind the last one
    double device_s = 0.0;         ///< its device time
    std::int64_t returned_ns = 0;  ///< when read() returned it (host clock)
};

/// A command written, until the device says when it took effect.
struct PendingWrite {
    std::uint64_t write = 0;  ///< the write() call, from 1 (0: an empty slot)
    Basis from;
    std::int64_t written_ns = 0;  ///< when write() was called (host clock)
    bool measured = false;
};
/// Commands whose acknowledgement may still come: more than any device names back (the open
/// protocol's applied_lag: 254; the sim: 10 periods).
constexpr std::size_t kPendingWrites = 1024;

DelayStats stats_of(std::vector<double> values) {
    DelayStats s;
    if (values.empty()) return s;
    std::sort(values.begin(), values.end());
    s.p50 = servo::sorted_quantile(values, 0.50);
    s.p99 = servo::sorted_quantile(values, 0.99);
    s.max = values.back();
    return s;
}

/// `value` (>= 0) rounded up to a multiple of `step`; a multiple (to 1e-9 of a step) stays,
/// and 0 is 0 (not -0).
double round_up_to(double value, double step) {
    const double rounded = std::ceil(value / step - 1e-9) * step;
    return rounded > 0.0 ? rounded : 0.0;
}

void summarise_delay(const std::vector<double>& delay_s, const std::vector<double>& host_s,
                     DiagReport& r) {
    r.delay_commands = delay_s.size();
    r.delay_measured = !delay_s.empty();
    if (!r.delay_measured) {
        std::ostringstream why;
        const std::uint64_t bad = r.bad_ack_command + r.bad_ack_time + r.acausal;
        if (r.replies == 0) {
            why << "no sample arrived";
        } else if (r.applied_unsupported > 0 && bad == 0 && r.applied_none == 0) {
            if (r.protocol_version == 1) {
                why << "the device speaks protocol version 1, whose samples do not say when a "
                       "command took effect: version 2's applied_lag and applied_age_us "
                       "(docs/protocol.md 4.6) are missing; a firmware on version 2 makes it "
                       "measurable";
            } else {
                why << "the " << r.plugin
                    << " device does not say when a command took effect (Sample::applied)";
            }
        } else if (bad > 0) {
            why << "no acknowledgement of the device could be used: " << bad
                << " were bad (counted below)";
        } else {
            why << "the device never named a command in effect";
        }
        r.delay_missing = why.str();
        return;
    }
    std::vector<double> link_s(delay_s.size());
    double least_link_s = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < delay_s.size(); ++i) {
        link_s[i] = delay_s[i] - host_s[i];
        least_link_s = std::min(least_link_s, link_s[i]);
    }
    r.delay_s = stats_of(delay_s);
    r.host_s = stats_of(host_s);
    r.link_s = stats_of(link_s);
    // A link and a device take time: a real-time device clock never shows less delay than
    // the host held the sample (1 us for the two clocks' resolutions).
    r.delay_split = !r.lockstep && least_link_s >= -1e-6;
    r.recommended_delay_s =
        round_up_to(r.delay_s.p99 * r.rate_hz, kDelayRoundingPeriods) / r.rate_hz;
}
}  // namespace

DiagReport run_link_diag(const Config& config, const DiagOptions& options, std::ostream& log) {
    if (!kDiagDuration.contains(options.duration_s)) {
        input::reject_out_of_range("--duration", options.duration_s, kDiagDuration);
    }
    device::DeviceHandle device = open_device(config, options.lockstep);
    const device::DeviceInfo info = device->info();

    DiagReport report;
    report.plugin = info.name;
    report.serial = info.serial;
    report.axes = info.axes;
    report.rate_hz = config.servo.rate_hz;
    report.lockstep = options.lockstep;
    report.samples_at_read = info.samples_at_read;
    report.paced = info.paces_loop;
    report.protocol_version = info.protocol_version;
    report.configured_delay_s = config.device.model.delay_s;
    const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / config.servo.rate_hz));
    const auto exchanges =
        static_cast<std::uint64_t>(std::llround(options.duration_s * config.servo.rate_hz));
    std::vector<double> rtt_us;
    std::vector<double> host_s;
    std::vector<double> device_s;
    std::vector<double> delay_s;       // per measured command: D, device clock
    std::vector<double> delay_host_s;  // ... and its host part, host clock
    rtt_us.reserve(exchanges);
    host_s.reserve(exchanges);
    device_s.reserve(exchanges);
    delay_s.reserve(exchanges);
    delay_host_s.reserve(exchanges);
    std::vector<PendingWrite> pending(kPendingWrites);
    log << "haptic-tune diag: " << info.name
        << (info.serial.empty() ? "" : " serial " + info.serial) << ", " << exchanges
        << " exchanges at " << config.servo.rate_hz << " Hz, zero force\n";

    const servo::Command zero{};  // disabled: the device outputs no force
    servo::Sample sample;
    bool have_sequence = false;
    bool previous_no_reply = false;
    std::uint64_t late_after_no_reply = 0;  // no-reply exchanges that a late reply explains
    std::uint64_t last_sequence = 0;
    bool have_time = false;
    double last_device_s = 0.0;
    Basis basis;               // the sample the next command is computed from
    std::uint64_t writes = 0;  // write() calls: Sample::applied_write counts them the same way

    // A command's delay, once the device says when it took effect.
    const auto measure = [&](std::uint64_t write, double applied_s) {
        if (write == 0 || write > writes) {
            ++report.bad_ack_command;  // a command diag never wrote
            return;
        }
        PendingWrite& p = pending[write % kPendingWrites];
        if (p.write != write || p.measured || !p.from.sound) return;
        p.measured = true;
        const double d = applied_s - p.from.device_s;
        if (d < 0.0) {
            ++report.acausal;  // in effect before the sample it was computed from was taken
            return;
        }
        delay_s.push_back(d);
        delay_host_s.push_back(static_cast<double>(p.written_ns - p.from.returned_ns) * 1e-9);
    };
    // One read's outcome: the counts, the device's clock and acknowledgement, the next basis.
    // True when a sample arrived.
    const auto take = [&](IoResult read, std::int64_t returned_ns) {
        if (read != IoResult::ok || (sample.status & servo::kStatusDropped) != 0u) {
            if (read != IoResult::disconnected) ++report.no_reply;
            previous_no_reply = read != IoResult::disconnected;
            basis = Basis{};  // the next command has no fresh sample behind it
            return false;
        }
        if ((sample.status & servo::kStatusLate) != 0u) {
            ++report.late;
            // A protocol device flags the sample after the one that missed its deadline.
            if (previous_no_reply) ++late_after_no_reply;
        }
        previous_no_reply = false;
        if (have_sequence && sample.sequence > last_sequence + 1) {
            report.sequence_gaps += sample.sequence - last_sequence - 1;
        }
        have_sequence = true;
        last_sequence = sample.sequence;
        bool sound = true;
        if (have_time && sample.device_time_s < last_device_s) {
            ++report.clock_backwards;
            sound = false;  // compared with the last sound sample from now on
        } else {
            have_time = true;
            last_device_s = sample.device_time_s;
        }
        switch (sample.applied) {
            case servo::AppliedReport::unsupported:
                ++report.applied_unsupported;
                break;
            case servo::AppliedReport::none:
                ++report.applied_none;
                break;
            case servo::AppliedReport::bad_command:
                ++report.bad_ack_command;
                break;
            case servo::AppliedReport::bad_time:
                ++report.bad_ack_time;
                break;
            case servo::AppliedReport::reported:
                if (sound) measure(sample.applied_write, sample.applied_time_s);
                break;
        }
        basis = Basis{sound, sample.device_time_s, returned_ns};
        return true;
    };
    const auto write_zero = [&](std::int64_t written_ns) {
        ++writes;
        pending[writes % kPendingWrites] = PendingWrite{writes, basis, written_ns, false};
        return device->write(zero);
    };

    if (!info.samples_at_read) {
        // The first sample, before the first command (a protocol device polls for it).
        (void)take(device->read(sample), servo::monotonic_now_ns());
        report.no_reply = 0;
        report.applied_unsupported = report.applied_none = 0;
        previous_no_reply = false;
    }
    const std::int64_t start_ns = servo::monotonic_now_ns();
    std::int64_t deadline_ns = start_ns;
    for (std::uint64_t i = 0; i < exchanges; ++i) {
        if (!options.lockstep && !info.paces_loop) {
            deadline_ns += period_ns;
            if (servo::monotonic_now_ns() > deadline_ns) {
                ++report.overruns;
                deadline_ns = servo::monotonic_now_ns();  // skip ahead, never burst
            } else {
                servo::sleep_until_monotonic_ns(deadline_ns);
            }
        }
        IoResult written = IoResult::ok;
        IoResult read = IoResult::ok;
        bool replied = false;
        std::int64_t began_ns = 0;
        std::int64_t answered_ns = 0;
        if (info.samples_at_read) {
            // The daemon's order: a fresh sample, then the command computed from it.
            began_ns = servo::monotonic_now_ns();
            read = device->read(sample);
            answered_ns = servo::monotonic_now_ns();
            replied = take(read, answered_ns);
            written = write_zero(servo::monotonic_now_ns());
        } else {
            // Write, then wait for its answer: the round trip. The answer is the sample the
            // next command is computed from, as in the daemon, whose tick reads it then.
            began_ns = servo::monotonic_now_ns();
            written = write_zero(began_ns);
            read = device->read(sample);
            answered_ns = servo::monotonic_now_ns();
            replied = take(read, answered_ns);
        }
        const std::int64_t done_ns = servo::monotonic_now_ns();
        ++report.exchanges;
        if (written == IoResult::disconnected || read == IoResult::disconnected) {
            ++report.disconnects;
        } else if (written == IoResult::error || read == IoResult::error) {
            ++report.errors;
        }
        if (!replied) continue;
        ++report.replies;
        rtt_us.push_back(
            static_cast<double>((info.samples_at_read ? done_ns : answered_ns) - began_ns) * 1e-3);
        host_s.push_back(static_cast<double>(answered_ns - start_ns) * 1e-9);
        device_s.push_back(sample.device_time_s);
    }
    report.duration_s = static_cast<double>(servo::monotonic_now_ns() - start_ns) * 1e-9;
    device->close();

    report.lost = report.no_reply - late_after_no_reply;
    std::vector<double> sorted = rtt_us;
    std::sort(sorted.begin(), sorted.end());
    report.rtt_p50_us = servo::sorted_quantile(sorted, 0.50);
    report.rtt_p90_us = servo::sorted_quantile(sorted, 0.90);
    report.rtt_p99_us = servo::sorted_quantile(sorted, 0.99);
    report.rtt_p999_us = servo::sorted_quantile(sorted, 0.999);
    report.rtt_max_us = sorted.empty() ? 0.0 : sorted.back();
    double sum = 0.0;
    for (const double r : sorted) sum += r;
    report.rtt_mean_us = sorted.empty() ? 0.0 : sum / static_cast<double>(sorted.size());
    for (std::size_t b = 0; b + 1 < std::size(kEdgesUs); ++b) {
        RttBin bin{kEdgesUs[b], kEdgesUs[b + 1], 0};
        for (const double r : sorted) {
            if (r >= bin.lo_us && r < bin.hi_us) ++bin.count;
        }
        report.rtt_histogram.push_back(bin);
    }
    if (!options.lockstep) fit_clock(host_s, device_s, report);
    summarise_delay(delay_s, delay_host_s, report);
    return report;
}

namespace {

/// The configured delay is more than kDelayRoundingPeriods below the measured p99.
bool delay_understated(const DiagReport& r) {
    return r.delay_measured &&
           r.delay_s.p99 * r.rate_hz > r.configured_delay_s * r.rate_hz + kDelayRoundingPeriods;
}

std::string delay_text(const DiagReport& r) {
    std::ostringstream s;
    s << std::fixed;
    if (!r.delay_measured) {
        s << "loop delay: not measured: " << r.delay_missing
          << ". No value for [device.model] delay can be given from this run: set it from "
             "the device's documentation (docs/stability-models.md)\n";
    } else {
        const auto ms = [](double seconds) { return seconds * 1e3; };
        const auto periods = [&r](double seconds) { return seconds * r.rate_hz; };
        s << std::setprecision(3)
          << "loop delay (encoder sample -> force in effect, device clock), " << r.delay_commands
          << " commands: p50 " << ms(r.delay_s.p50) << " ms (" << periods(r.delay_s.p50)
          << " periods), p99 " << ms(r.delay_s.p99) << " ms (" << periods(r.delay_s.p99)
          << " periods), max " << ms(r.delay_s.max) << " ms\n";
        s << "  host (read() of the sample -> write() of its command, host clock): p50 "
          << ms(r.host_s.p50) << " ms, p99 " << ms(r.host_s.p99) << " ms\n";
        if (r.delay_split) {
            s << "  link and device (the rest: the reply's and the command's trips, the device's "
                 "processing): p50 "
              << ms(r.link_s.p50) << " ms, p99 " << ms(r.link_s.p99) << " ms\n";
        } else {
            s << "  link and device: not split: "
              << (r.lockstep ? "virtual time (--lockstep), the host's part is not physical"
                             : "some delays are shorter than the host held their sample, so "
                               "the device's clock does not run with the host's (a virtual-"
                               "time device such as the reference emulator)")
              << "\n";
        }
        const double recommended_periods = periods(r.recommended_delay_s);
        if (recommended_periods < tune::kMaxDelayPeriods) {
            s << std::defaultfloat << std::setprecision(6)
              << "  [device.model] delay = " << r.recommended_delay_s
              << "  # s: the p99 rounded up to the next " << kDelayRoundingPeriods << " period ("
              << recommended_periods << " periods), a conservative value\n"
              << std::fixed;
        } else {
            s << "  no value for [device.model] delay: the p99 is beyond the stability models' "
                 "range (under "
              << std::setprecision(0) << tune::kMaxDelayPeriods << " periods)\n";
        }
        if (!delay_understated(r)) {
            s << std::defaultfloat << std::setprecision(6)
              << "  the config's [device.model] delay = " << r.configured_delay_s << " s ";
            if (r.configured_delay_s * r.rate_hz >= periods(r.delay_s.p99) - 1e-9) {
                s << "covers it\n";
            } else {
                s << "is within " << kDelayRoundingPeriods << " period of its p99\n";
            }
            s << std::fixed;
        }
    }
    s << "acknowledgements: " << r.applied_unsupported << " samples without one, " << r.applied_none
      << " naming no command yet; bad: " << r.bad_ack_command << " naming a command never sent, "
      << r.bad_ack_time << " with inconsistent times, " << r.acausal
      << " with a force before its sample; device clock going backwards: " << r.clock_backwards
      << "\n";
    return s.str();
}

}  // namespace

double DiagReport::percent_of_exchanges(std::uint64_t n) const noexcept {
    return exchanges == 0 ? 0.0 : 100.0 * static_cast<double>(n) / static_cast<double>(exchanges);
}

DiagVerdict DiagReport::verdict() const {
    using Level = DiagVerdict::Level;
    const double period_us = 1e6 / rate_hz;
    const std::uint64_t bad_acks = bad_ack_command + bad_ack_time + acausal;
    std::ostringstream s;
    if (replies == 0) return {Level::fail, "FAIL: the device never answered"};
    if (!paced && rtt_p99_us > 0.3 * period_us) {
        s << std::fixed << std::setprecision(0) << "WARN: p99 round trip " << rtt_p99_us
          << " us is over 30 % of the " << period_us
          << " us period; replies will miss the tick (serial: FTDI latency timer? "
          << "docs/transport-serial.md)";
        return {Level::warn, s.str()};
    }
    if (percent_of_exchanges(lost + late) > 0.1) {
        return {Level::warn, "WARN: more than 0.1 % of exchanges lost or late"};
    }
    if (bad_acks + clock_backwards > 0) {
        s << "WARN: the device's timestamps or acknowledgements contradict themselves (" << bad_acks
          << (bad_acks == 1 ? " bad acknowledgement, " : " bad acknowledgements, ")
          << clock_backwards << (clock_backwards == 1 ? " sample" : " samples")
          << " with the device clock going backwards): its firmware clock or its command "
             "bookkeeping is wrong";
        return {Level::warn, s.str()};
    }
    if (delay_understated(*this)) {
        s << std::setprecision(6) << "WARN: [device.model] delay = " << configured_delay_s
          << " s is below the measured loop delay (p99 " << delay_s.p99
          << " s): the stability check assumes less delay than the loop has; set delay = "
          << recommended_delay_s;
        return {Level::warn, s.str()};
    }
    s << std::fixed << "ok: the link keeps up with " << std::setprecision(0) << rate_hz << " Hz";
    return {Level::ok, s.str()};
}

std::string diag_text(const DiagReport& r) {
    std::ostringstream s;
    s << std::fixed;
    const auto percent = [&](std::uint64_t n) { return r.percent_of_exchanges(n); };
    s << "link: " << r.plugin << (r.serial.empty() ? "" : " serial " + r.serial) << ", "
      << servo::axes_text(r.axes) << ", " << std::setprecision(0) << r.rate_hz << " Hz, "
      << r.exchanges << " exchanges in " << std::setprecision(2) << r.duration_s << " s"
      << (r.paced && !r.lockstep ? ", paced by the device (each round trip includes the wait for "
                                   "its period boundary)"
                                 : "")
      << "\n";
    s << std::setprecision(1) << "round trip (write -> reply), us: p50 " << r.rtt_p50_us << "  p90 "
      << r.rtt_p90_us << "  p99 " << r.rtt_p99_us << "  p99.9 " << r.rtt_p999_us << "  max "
      << r.rtt_max_us << "  mean " << r.rtt_mean_us << "\n";
    std::uint64_t most = 1;
    for (const RttBin& b : r.rtt_histogram) most = std::max(most, b.count);
    for (const RttBin& b : r.rtt_histogram) {
        std::ostringstream range;
        range << std::setprecision(0) << std::fixed << b.lo_us << "-"
              << (std::isinf(b.hi_us) ? std::string("inf")
                                      : std::to_string(static_cast<int>(b.hi_us)));
        const auto bar = static_cast<std::size_t>(40.0 * static_cast<double>(b.count) /
                                                  static_cast<double>(most));
        s << "  " << std::setw(12) << range.str() << " us " << std::setw(8) << b.count << " "
          << std::string(bar, '#') << "\n";
    }
    s << std::setprecision(3) << "no reply: " << r.no_reply << " (" << percent(r.no_reply)
      << " %), late: " << r.late << " (" << percent(r.late) << " %), lost: " << r.lost << " ("
      << percent(r.lost) << " %), sequence gaps: " << r.sequence_gaps
      << ", disconnects: " << r.disconnects << ", errors: " << r.errors
      << ", host overruns: " << r.overruns << "\n";
    if (r.clock_fit) {
        s << std::setprecision(1) << "device clock: drift " << r.clock_drift_ppm
          << " ppm against the host, jitter " << r.clock_jitter_us << " us RMS\n";
    } else {
        s << "device clock: not enough samples for a drift estimate\n";
    }
    s << delay_text(r);
    s << "verdict: " << r.verdict().text << "\n";
    return s.str();
}

std::string diag_json(const DiagReport& r) {
    nlohmann::ordered_json j;
    j["plugin"] = r.plugin;
    j["serial"] = r.serial;
    j["axes"] = r.axes;
    j["rate_hz"] = r.rate_hz;
    j["duration_s"] = r.duration_s;
    j["exchanges"] = r.exchanges;
    j["replies"] = r.replies;
    j["rtt_us"] = {{"p50", r.rtt_p50_us},   {"p90", r.rtt_p90_us}, {"p99", r.rtt_p99_us},
                   {"p999", r.rtt_p999_us}, {"max", r.rtt_max_us}, {"mean", r.rtt_mean_us}};
    nlohmann::ordered_json bins = nlohmann::ordered_json::array();
    for (const RttBin& b : r.rtt_histogram) {
        nlohmann::ordered_json bin;
        bin["lo_us"] = b.lo_us;
        bin["hi_us"] =
            std::isinf(b.hi_us) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(b.hi_us);
        bin["count"] = b.count;
        bins.push_back(bin);
    }
    j["rtt_histogram"] = bins;
    j["no_reply"] = r.no_reply;
    j["late"] = r.late;
    j["lost"] = r.lost;
    j["sequence_gaps"] = r.sequence_gaps;
    j["disconnects"] = r.disconnects;
    j["errors"] = r.errors;
    j["host_overruns"] = r.overruns;
    j["paced_by_device"] = r.paced;
    j["clock_drift_ppm"] =
        r.clock_fit ? nlohmann::ordered_json(r.clock_drift_ppm) : nlohmann::ordered_json(nullptr);
    j["clock_jitter_us"] =
        r.clock_fit ? nlohmann::ordered_json(r.clock_jitter_us) : nlohmann::ordered_json(nullptr);
    const auto stats = [](const DelayStats& d, double scale) {
        return nlohmann::ordered_json{
            {"p50", d.p50 * scale}, {"p99", d.p99 * scale}, {"max", d.max * scale}};
    };
    const auto null = nlohmann::ordered_json(nullptr);
    nlohmann::ordered_json delay;
    delay["measured"] = r.delay_measured;
    delay["missing"] = r.delay_measured ? null : nlohmann::ordered_json(r.delay_missing);
    delay["protocol_version"] =
        r.protocol_version > 0 ? nlohmann::ordered_json(r.protocol_version) : null;
    delay["commands"] = r.delay_commands;
    delay["s"] = r.delay_measured ? stats(r.delay_s, 1.0) : null;
    delay["periods"] = r.delay_measured ? stats(r.delay_s, r.rate_hz) : null;
    delay["host_s"] = r.delay_measured ? stats(r.host_s, 1.0) : null;
    delay["split"] = r.delay_split;
    delay["link_device_s"] = r.delay_measured && r.delay_split ? stats(r.link_s, 1.0) : null;
    const bool in_range =
        r.delay_measured && r.recommended_delay_s * r.rate_hz < tune::kMaxDelayPeriods;
    delay["recommended_s"] = in_range ? nlohmann::ordered_json(r.recommended_delay_s) : null;
    delay["recommended_rule"] = "p99 rounded up to the next 0.05 period";
    delay["configured_s"] = r.configured_delay_s;
    delay["samples_without_acknowledgement"] = r.applied_unsupported;
    delay["naming_no_command"] = r.applied_none;
    delay["bad_command"] = r.bad_ack_command;
    delay["bad_time"] = r.bad_ack_time;
    delay["acausal"] = r.acausal;
    delay["clock_backwards"] = r.clock_backwards;
    j["loop_delay"] = delay;
    const DiagVerdict verdict = r.verdict();
    j["verdict"] = {{"ok", verdict.ok()}, {"text", verdict.text}};
    return j.dump(2);
}

}  // namespace hapticd::daemon
