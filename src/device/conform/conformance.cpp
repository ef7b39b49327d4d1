#include "hapticd/device/conform/conformance.hpp"

#include <cmath>
#include <stdexcept>

#include "checks.hpp"

namespace hapticd::device::conform {

namespace proto = protocol;

std::string_view to_string(Outcome outcome) noexcept {
    switch (outcome) {
        case Outcome::pass:
            return "pass";
        case Outcome::fail:
            return "FAIL";
        case Outcome::skipped:
            break;
    }
    return "skipped";
}

bool ConformReport::passed() const noexcept {
    for (const CheckResult& check : checks) {
        if (check.outcome != Outcome::pass) return false;
    }
    return !checks.empty();
}

namespace {

void validate(const ConformOptions& o) {
    if (!(std::isfinite(o.rate_hz) && o.rate_hz > 0.0)) {
        throw std::invalid_argument("conform: rate_hz must be finite and > 0");
    }
    const double period_us = 1e6 / o.rate_hz;
    if (o.watchdog_timeout_us < 2.0 * period_us ||
        o.watchdog_timeout_us > proto::kMaxWatchdogTimeoutUs) {
        throw std::invalid_argument(
            "conform: the watchdog timeout " + std::to_string(o.watchdog_timeout_us) +
            " us is out of range: allowed two periods (" +
            std::to_string(static_cast<long>(std::ceil(2.0 * period_us))) + " us) to 1000000 us");
    }
    if (o.timing_exchanges < 10 || o.timing_exchanges > 1'000'000) {
        throw std::invalid_argument("conform: timing exchanges " +
                                    std::to_string(o.timing_exchanges) +
                                    " is out of range: allowed 10 to 1000000");
    }
    if (o.reply_timeout_ns <= 0) throw std::invalid_argument("conform: reply timeout must be > 0");
}

CheckResult skipped(const CheckId& check, const std::string& why) {
    CheckResult result;
    result.name = check.name;
    result.section = check.section;
    result.outcome = Outcome::skipped;
    result.detail = why;
    return result;
}

}  // namespace

ConformReport run_conformance(link::FrameLink& link, const ConformOptions& options) {
    validate(options);
    ConformReport report;
    report.device = link.describe();
    link.open();
    ConformHost host(link, options);
    report.checks.push_back(check_handshake(host, report.identity));
    if (!report.identity) {
        const std::string why = "needs the handshake";
        for (const CheckId& check : kAllChecks) {
            if (&check != &kHandshake) report.checks.push_back(skipped(check, why));
        }
        link.close();
        return report;
    }
    const proto::Identity& identity = *report.identity;
    report.checks.push_back(check_versions(host, identity));
    report.checks.push_back(check_sessions(host));
    report.checks.push_back(check_configure(host, identity));
    report.checks.push_back(check_commands(host, identity));
    report.checks.push_back(check_timing(host, identity));
    report.checks.push_back(check_frame_errors(host));
    report.checks.push_back(check_message_errors(host, identity));
    report.checks.push_back(check_watchdog(host, identity));
    report.checks.push_back(check_bye(host));
    link.close();
    return report;
}

}  // namespace hapticd::device::conform
