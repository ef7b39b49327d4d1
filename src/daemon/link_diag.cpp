// Link diagnostics: the device at zero force, one exchange per period (link_diag.hpp).
#include "hapticd/daemon/link_diag.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "hapticd/device/plugin_loader.hpp"

namespace hapticd::daemon {
namespace {

using servo::IoResult;

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Histogram edges, us: fine below a millisecond, where a 1 kHz loop lives.
constexpr double kEdgesUs[] = {0, 25, 50, 100, 200, 300, 500, 750, 1000, 2000, 5000, 10000, kInf};

std::int64_t now_ns() {
    timespec t{};
    clock_gettime(CLOCK_MONOTONIC, &t);
    return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

void sleep_until_ns(std::int64_t deadline_ns) {
    timespec t{};
    t.tv_sec = static_cast<time_t>(deadline_ns / 1'000'000'000);
    t.tv_nsec = static_cast<long>(deadline_ns % 1'000'000'000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
    }
}

double percentile(const std::vector<double>& sorted, double p) {
    if (sorted.empty()) return 0.0;
    const auto index =
        static_cast<std::size_t>(std::ceil(p * static_cast<double>(sorted.size()))) - 1;
    return sorted[std::min(index, sorted.size() - 1)];
}

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

}  // namespace

DiagReport run_link_diag(const Config& config, const DiagOptions& options, std::ostream& log) {
    if (!(options.duration_s > 0.0) || options.duration_s > 3600.0) {
        std::ostringstream m;
        m << "--duration " << options.duration_s << " is not allowed: must be > 0 and <= 3600 s";
        throw std::invalid_argument(m.str());
    }
    device::DeviceHandle device = device::load_device(config.device.plugin);
    device::DeviceConfig device_config;
    device_config.axes = config.device.axes;
    device_config.rate_hz = config.servo.rate_hz;
    device_config.lockstep = options.lockstep;
    device_config.plugin_table_toml = config.device.plugin_table_toml;
    device_config.source = config.source;
    try {
        device->open(device_config);
    } catch (...) {
        device->close();
        throw;
    }
    const device::DeviceInfo info = device->info();

    DiagReport report;
    report.plugin = info.name;
    report.serial = info.serial;
    report.axes = info.axes;
    report.rate_hz = config.servo.rate_hz;
    const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / config.servo.rate_hz));
    const auto exchanges =
        static_cast<std::uint64_t>(std::llround(options.duration_s * config.servo.rate_hz));
    std::vector<double> rtt_us;
    std::vector<double> host_s;
    std::vector<double> device_s;
    rtt_us.reserve(exchanges);
    host_s.reserve(exchanges);
    device_s.reserve(exchanges);
    log << "haptic-tune diag: " << info.name
        << (info.serial.empty() ? "" : " serial " + info.serial) << ", " << exchanges
        << " exchanges at " << config.servo.rate_hz << " Hz, zero force\n";

    const servo::Command zero{};  // disabled: the device outputs no force
    servo::Sample sample;
    (void)device->read(sample);  // the first sample, before the first command
    bool have_sequence = (sample.status & servo::kStatusDropped) == 0u;
    bool previous_no_reply = false;
    std::uint64_t late_after_no_reply = 0;  // no-reply exchanges that a late reply explains
    std::uint64_t last_sequence = sample.sequence;
    const std::int64_t start_ns = now_ns();
    std::int64_t deadline_ns = start_ns;
    for (std::uint64_t i = 0; i < exchanges; ++i) {
        if (!options.lockstep) {
            deadline_ns += period_ns;
            if (now_ns() > deadline_ns) {
                ++report.overruns;
                deadline_ns = now_ns();  // skip ahead, never burst
            } else {
                sleep_until_ns(deadline_ns);
            }
        }
        const std::int64_t sent_ns = now_ns();
        const IoResult written = device->write(zero);
        const IoResult read = device->read(sample);
        const std::int64_t answered_ns = now_ns();
        ++report.exchanges;
        if (written == IoResult::disconnected || read == IoResult::disconnected) {
            ++report.disconnects;
        } else if (written == IoResult::error || read == IoResult::error) {
            ++report.errors;
        }
        if (read != IoResult::ok || (sample.status & servo::kStatusDropped) != 0u) {
            if (read != IoResult::disconnected) ++report.no_reply;
            previous_no_reply = read != IoResult::disconnected;
            continue;
        }
        ++report.replies;
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
        rtt_us.push_back(static_cast<double>(answered_ns - sent_ns) * 1e-3);
        host_s.push_back(static_cast<double>(answered_ns - start_ns) * 1e-9);
        device_s.push_back(sample.device_time_s);
    }
    report.duration_s = static_cast<double>(now_ns() - start_ns) * 1e-9;
    device->close();

    report.lost = report.no_reply - late_after_no_reply;
    std::vector<double> sorted = rtt_us;
    std::sort(sorted.begin(), sorted.end());
    report.rtt_p50_us = percentile(sorted, 0.50);
    report.rtt_p90_us = percentile(sorted, 0.90);
    report.rtt_p99_us = percentile(sorted, 0.99);
    report.rtt_p999_us = percentile(sorted, 0.999);
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
    return report;
}

std::string diag_text(const DiagReport& r) {
    std::ostringstream s;
    s << std::fixed;
    const double period_us = 1e6 / r.rate_hz;
    const auto percent = [&](std::uint64_t n) {
        return r.exchanges == 0 ? 0.0
                                : 100.0 * static_cast<double>(n) / static_cast<double>(r.exchanges);
    };
    s << "link: " << r.plugin << (r.serial.empty() ? "" : " serial " + r.serial) << ", " << r.axes
      << (r.axes == 1 ? " axis" : " axes") << ", " << std::setprecision(0) << r.rate_hz << " Hz, "
      << r.exchanges << " exchanges in " << std::setprecision(2) << r.duration_s << " s\n";
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
    // Verdicts: what a 1 kHz servo needs from the link.
    s << "verdict: ";
    if (r.replies == 0) {
        s << "FAIL: the device never answered\n";
    } else if (r.rtt_p99_us > 0.3 * period_us) {
        s << std::setprecision(0) << "WARN: p99 round trip " << r.rtt_p99_us
          << " us is over 30 % of the " << period_us
          << " us period; replies will miss the tick (serial: FTDI latency timer? "
          << "docs/transport-serial.md)\n";
    } else if (percent(r.lost + r.late) > 0.1) {
        s << "WARN: more than 0.1 % of exchanges lost or late\n";
    } else {
        s << "ok: the link keeps up with " << std::setprecision(0) << r.rate_hz << " Hz\n";
    }
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
    j["clock_drift_ppm"] =
        r.clock_fit ? nlohmann::ordered_json(r.clock_drift_ppm) : nlohmann::ordered_json(nullptr);
    j["clock_jitter_us"] =
        r.clock_fit ? nlohmann::ordered_json(r.clock_jitter_us) : nlohmann::ordered_json(nullptr);
    return j.dump(2);
}

}  // namespace hapticd::daemon
