// The checks of sessions and their setup (checks.hpp): handshake, versions, sessions,
// configure, bye.
#include <cmath>
#include <sstream>

#include "checks.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"

namespace hapticd::device::conform {

namespace proto = protocol;

namespace {

std::string hex(std::uint32_t value) {
    std::ostringstream out;
    out << "0x" << std::hex << value;
    return out.str();
}

}  // namespace

CheckResult verdict(const CheckId& check, const Finding& finding, std::string evidence) {
    CheckResult result;
    result.name = check.name;
    result.section = check.section;
    result.outcome = finding.failed ? Outcome::fail : Outcome::pass;
    if (finding.failed) {
        result.detail = finding.detail;
    } else {
        result.detail = std::move(evidence);
    }
    return result;
}

CheckResult check_handshake(ConformHost& host, std::optional<proto::Identity>& identity) {
    Finding f;
    std::string why;
    const std::uint32_t session = host.new_session();
    identity = host.hello(session, proto::kMinVersion, proto::kMaxVersion, why);
    if (!identity) {
        f.fail(why + " (5.1: a device answers hello with its identity, in the session's id)");
        return verdict(kHandshake, f, "");
    }
    const proto::Identity& id = *identity;
    const std::uint32_t period_us = host.period_us();
    if (id.period_us != period_us) {
        f.fail("the identity's period is " + std::to_string(id.period_us) +
               " us; the host's rate needs " + std::to_string(period_us) + " us ([servo] rate_hz)");
    }
    if (id.watchdog_timeout_us < 2 * id.period_us ||
        id.watchdog_timeout_us > proto::kMaxWatchdogTimeoutUs) {
        f.fail("the identity's watchdog timeout is " + std::to_string(id.watchdog_timeout_us) +
               " us: 5.4 allows two periods (" + std::to_string(2 * id.period_us) + " us) to 1 s");
    }
    const std::string& expected = host.options().expected_serial;
    if (!expected.empty() && !proto::serial_matches(id, expected)) {
        f.fail("the serial number is '" + std::string(id.serial_number()) + "', not '" + expected +
               "' (the wrong device?)");
    }
    std::ostringstream evidence;
    evidence << "identity in version " << int{id.version} << (id.paced() ? " (paced)" : "") << ": "
             << int{id.axes} << (id.axes == 1 ? " axis" : " axes") << ", period " << id.period_us
             << " us, force limit " << 1e-6 * id.force_limit_un << " N, " << id.counts_per_meter
             << " counts/m, watchdog " << id.watchdog_timeout_us << " us, serial "
             << id.serial_number() << ", firmware " << hex(id.firmware_version);
    return verdict(kHandshake, f, evidence.str());
}

CheckResult check_versions(ConformHost& host, const proto::Identity& identity) {
    Finding f;
    std::string why;
    std::vector<std::string> seen;
    // Version 1 only: spoken, or refused with the device's range.
    const std::uint32_t s1 = host.new_session();
    host.drain();
    host.send(proto::Hello{s1, 1, 1});
    const std::optional<proto::Message> v1 = host.receive_for(s1);
    if (const auto* id = as<proto::Identity>(v1); id != nullptr && id->version == 1) {
        seen.push_back("speaks version 1");
    } else if (as_error(v1, proto::ErrorCode::unsupported_version) != nullptr) {
        seen.push_back("does not speak version 1 (unsupported_version)");
    } else {
        f.fail("hello offering version 1 only answered with " + host.describe(v1) +
               " (3.2: an identity in version 1, or unsupported_version)");
    }
    // A range it cannot speak.
    const std::uint32_t s2 = host.new_session();
    host.send(proto::Hello{s2, 200, 255});
    const std::optional<proto::Message> none = host.receive_for(s2);
    if (const auto* e = as_error(none, proto::ErrorCode::unsupported_version)) {
        seen.push_back("versions 200..255 refused (unsupported_version, its range " +
                       std::to_string(e->detail & 0xFFu) + ".." +
                       std::to_string((e->detail >> 8) & 0xFFu) + ")");
    } else {
        f.fail("hello offering versions 200..255 answered with " + host.describe(none) +
               " (4.1: unsupported_version with the device's range)");
    }
    // The widest range: the highest version in common, as the handshake saw.
    const std::optional<proto::Identity> widest =
        host.hello(host.new_session(), proto::kMinVersion, proto::kMaxVersion, why);
    if (!widest) {
        f.fail(why);
        return verdict(kVersions, f, "");
    }
    if (widest->version != identity.version) {
        f.fail("versions 1..3 chose version " + std::to_string(widest->version) +
               " this time and " + std::to_string(identity.version) + " before");
    }
    // A frame of the session in another version.
    const std::uint8_t other = host.version() == 1 ? 2 : 1;
    host.send(proto::Poll{host.session(), other});
    const std::optional<proto::Message> wrong = host.receive_for(host.session());
    if (as_error(wrong, proto::ErrorCode::bad_version) != nullptr) {
        seen.push_back("a poll in version " + std::to_string(other) + " refused (bad_version)");
    } else {
        f.fail("a poll in version " + std::to_string(other) + " in a version-" +
               std::to_string(host.version()) + " session answered with " + host.describe(wrong) +
               " (3.2: bad_version)");
    }
    std::string evidence = "highest common version " + std::to_string(identity.version);
    for (const std::string& s : seen) evidence += "; " + s;
    return verdict(kVersions, f, evidence);
}

CheckResult check_sessions(ConformHost& host) {
    Finding f;
    std::string why;
    if (!host.hello(host.new_session(), proto::kMinVersion, proto::kMaxVersion, why)) {
        f.fail(why);
        return verdict(kSessions, f, "");
    }
    const std::uint32_t first = host.session();
    const std::uint8_t version = host.version();
    // A session id that is not the current one.
    const std::uint32_t stranger = first + 1 == 0 ? 1 : first + 1;
    host.send(proto::Poll{stranger, version});
    if (as_error(host.receive_for(stranger), proto::ErrorCode::wrong_session) == nullptr) {
        f.fail(
            "a poll with a session id that is not the current one was not refused with "
            "wrong_session");
    }
    // sample_sequence from 0, +1 per sample.
    for (std::uint32_t expected = 0; expected < 2; ++expected) {
        host.send(host.poll());
        const std::optional<proto::Message> reply = host.receive_for(first);
        const auto* sample = as<proto::EncoderSample>(reply);
        if (sample == nullptr) {
            f.fail("a poll answered with " + host.describe(reply));
        } else if (sample->sample_sequence != expected) {
            f.fail("sample " + std::to_string(expected) + " of a new session has sample_sequence " +
                   std::to_string(sample->sample_sequence) + " (4.6: from 0 in each session)");
        }
    }
    // A new hello ends the old session.
    if (!host.hello(host.new_session(), proto::kMinVersion, proto::kMaxVersion, why)) {
        f.fail(why);
        return verdict(kSessions, f, "");
    }
    host.send(proto::Poll{first, version});
    if (as_error(host.receive_for(first), proto::ErrorCode::wrong_session) == nullptr) {
        f.fail(
            "after a new hello, a poll of the old session was not refused with wrong_session "
            "(5.1: hello ends the current session)");
    }
    host.send(host.poll());
    const std::optional<proto::Message> first_of_second = host.receive_for(host.session());
    if (const auto* s = as<proto::EncoderSample>(first_of_second);
        s == nullptr || s->sample_sequence != 0) {
        f.fail("the first sample of the second session does not have sample_sequence 0");
    }
    // No session after bye.
    const std::uint32_t second = host.session();
    host.send(proto::Bye{second, version});
    (void)host.receive_for(second);
    host.send(proto::Poll{second, version});
    if (as_error(host.receive_for(second), proto::ErrorCode::no_session) == nullptr) {
        f.fail("a poll after bye was not refused with no_session");
    }
    return verdict(kSessions, f,
                   "wrong_session for a stranger's id and for the session a new hello ended; "
                   "sample_sequence 0, 1 in each new session; no_session after bye");
}

CheckResult check_configure(ConformHost& host, const proto::Identity& identity) {
    Finding f;
    std::string why;
    if (!host.hello(host.new_session(), proto::kMinVersion, proto::kMaxVersion, why)) {
        f.fail(why);
        return verdict(kConfigure, f, "");
    }
    const std::uint32_t two_periods = 2 * identity.period_us;
    for (const std::uint32_t bad : {two_periods - 1, proto::kMaxWatchdogTimeoutUs + 1}) {
        host.send(proto::Configure{host.session(), bad, host.version()});
        const std::optional<proto::Message> reply = host.receive_for(host.session());
        if (as_error(reply, proto::ErrorCode::out_of_range) == nullptr) {
            f.fail("configure(watchdog " + std::to_string(bad) + " us) answered with " +
                   host.describe(reply) + " (5.4: out_of_range outside [" +
                   std::to_string(two_periods) + " us, 1 s])");
        }
    }
    const std::uint32_t wanted = host.options().watchdog_timeout_us;
    host.send(proto::Configure{host.session(), wanted, host.version()});
    const std::optional<proto::Message> reply = host.receive_for(host.session());
    if (const auto* ack = as<proto::ConfigureAck>(reply)) {
        if (ack->watchdog_timeout_us != wanted) {
            f.fail("configure(watchdog " + std::to_string(wanted) + " us) acknowledged " +
                   std::to_string(ack->watchdog_timeout_us) + " us");
        }
    } else {
        f.fail("configure(watchdog " + std::to_string(wanted) + " us) answered with " +
               host.describe(reply));
    }
    return verdict(kConfigure, f,
                   "watchdog " + std::to_string(two_periods - 1) +
                       " us and 1000001 us refused "
                       "(out_of_range); " +
                       std::to_string(wanted) + " us acknowledged");
}

CheckResult check_bye(ConformHost& host) {
    Finding f;
    std::string why;
    if (!host.open_session(host.options().watchdog_timeout_us, why)) {
        f.fail(why);
        return verdict(kBye, f, "");
    }
    host.send(host.command(true));
    (void)host.receive_for(host.session());
    host.send(proto::Bye{host.session(), host.version()});
    const std::optional<proto::Message> ack = host.receive_for(host.session());
    if (as<proto::ByeAck>(ack) == nullptr) {
        f.fail("bye answered with " + host.describe(ack) + " (4.9: bye_ack)");
    }
    host.send(host.command(true));
    const std::optional<proto::Message> after = host.receive_for(host.session());
    if (as_error(after, proto::ErrorCode::no_session) == nullptr) {
        f.fail("a command after bye answered with " + host.describe(after) +
               " (5.1: no_session, nothing applied)");
    }
    return verdict(kBye, f,
                   "bye_ack, then a command refused with no_session (that the force is zero is "
                   "for an instrument on the motor)");
}

}  // namespace hapticd::device::conform
