// The checks of the exchanges in a session (checks.hpp): commands, timing, frame and message
// errors, the watchdog.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "checks.hpp"
#include "hapticd/device/protocol/crc32c.hpp"
#include "hapticd/device/protocol/reply_tracker.hpp"
#include "hapticd/servo/monotonic_clock.hpp"
#include "hapticd/servo/nearest_rank.hpp"

namespace hapticd::device::conform {

namespace proto = protocol;

namespace {

std::string number(double value, int digits = 3) {
    std::ostringstream out;
    out.precision(digits);
    out << value;
    return out.str();
}

/// A frame built by hand: `header` around `payload`, the CRC good unless `bad_crc`.
std::vector<std::byte> raw_frame(const proto::FrameHeader& header,
                                 std::span<const std::byte> payload) {
    std::vector<std::byte> out(proto::kHeaderSize + payload.size() + proto::kCrcSize);
    std::copy(payload.begin(), payload.end(), out.begin() + proto::kHeaderSize);
    (void)proto::finish_frame(header, out);
    return out;
}

/// Rewrites the CRC of a whole frame after its bytes were changed.
void fix_crc(std::vector<std::byte>& frame) {
    const std::size_t body = frame.size() - proto::kCrcSize;
    const std::uint32_t crc = proto::crc32c(std::span<const std::byte>(frame.data(), body));
    for (std::size_t i = 0; i < proto::kCrcSize; ++i) {
        frame[body + i] = static_cast<std::byte>((crc >> (8 * i)) & 0xFFu);
    }
}

template <typename M>
std::vector<std::byte> encoded(const M& message) {
    std::vector<std::byte> out(proto::kMaxFrameSize);
    out.resize(proto::encode(message, out).size);
    return out;
}

}  // namespace

CheckResult check_commands(ConformHost& host, const proto::Identity& identity) {
    Finding f;
    std::string why;
    if (!host.open_long_session(why)) {
        f.fail(why);
        return verdict(kCommands, f, "");
    }
    proto::ReplyTracker tracker;
    tracker.start(host.session(), host.version());
    constexpr int kCommandCount = 20;
    std::uint64_t last_time_us = 0;
    std::uint32_t last_sample = 0;
    std::uint32_t period_steps = 0;
    for (int i = 0; i < kCommandCount && !f.failed; ++i) {
        const proto::ForceCommand command = host.command(true);
        tracker.command_sent(command.sequence);
        host.send(command);
        const std::optional<proto::Message> reply = host.receive_for(host.session());
        const auto* sample = as<proto::EncoderSample>(reply);
        if (sample == nullptr) {
            f.fail("command " + std::to_string(command.sequence) + " answered with " +
                   host.describe(reply) + " (5.2: a sample within the period)");
            break;
        }
        if (sample->command_sequence != command.sequence) {
            f.fail("the sample answering command " + std::to_string(command.sequence) +
                   " names command " + std::to_string(sample->command_sequence));
        }
        if (i > 0 && sample->sample_sequence != last_sample + 1) {
            f.fail("sample_sequence went from " + std::to_string(last_sample) + " to " +
                   std::to_string(sample->sample_sequence) + " (4.6: +1 per sample)");
        }
        if (i > 0 && sample->time_us <= last_time_us) {
            f.fail("the device's clock went from " + std::to_string(last_time_us) + " to " +
                   std::to_string(sample->time_us) + " us");
        }
        if (i > 0 && sample->time_us - last_time_us == identity.period_us) ++period_steps;
        if (sample->faults != 0) {
            f.fail("a zero-force command was answered with faults 0x" +
                   std::to_string(sample->faults));
        }
        if (sample->axes != identity.axes) f.fail("a sample with the wrong number of axes");
        const proto::ReplyTracker::Result result = tracker.check(*sample);
        if (result.verdict != proto::ReplyTracker::Verdict::accept) {
            f.fail("the host's checks of 5.3 did not accept the sample answering command " +
                   std::to_string(command.sequence));
        }
        last_time_us = sample->time_us;
        last_sample = sample->sample_sequence;
    }
    const proto::ReplyTracker::Counters& counts = tracker.counters();
    if (counts.applied_bad_command + counts.applied_bad_time > 0) {
        f.fail("version 2's acknowledgements contradicted themselves " +
               std::to_string(counts.applied_bad_command + counts.applied_bad_time) +
               " times (5.3)");
    }
    if (host.version() >= 2 && counts.applied_reported == 0) {
        f.fail("no sample of a version-" + std::to_string(host.version()) +
               " session named the command in effect (4.6 applied_lag)");
    }
    // A gap in the command sequence is flagged.
    host.skip_sequences(5);
    host.send(host.command(true));
    const std::optional<proto::Message> gap = host.receive_for(host.session());
    const auto* gap_sample = as<proto::EncoderSample>(gap);
    if (gap_sample == nullptr || (gap_sample->status & proto::kSampleCommandGap) == 0) {
        f.fail("a command 6 after the last answered with " + host.describe(gap) +
               " (5.2: command_gap set)");
    }
    // The wrong number of axes: refused, nothing applied.
    proto::ForceCommand wrong = host.command(true);
    wrong.axes = static_cast<std::uint8_t>(identity.axes % proto::kMaxProtocolAxes + 1);
    host.send(wrong);
    const std::optional<proto::Message> refused = host.receive_for(host.session());
    if (as_error(refused, proto::ErrorCode::wrong_axes) == nullptr) {
        f.fail("a command for " + std::to_string(wrong.axes) + " axes answered with " +
               host.describe(refused) + " (4.5: wrong_axes)");
    }
    host.send(host.poll());
    const std::optional<proto::Message> after_reply = host.receive_for(host.session());
    const auto* after = as<proto::EncoderSample>(after_reply);
    if (after == nullptr || after->command_sequence != wrong.sequence - 1) {
        f.fail("after the refused command the sample names command " +
               (after ? std::to_string(after->command_sequence) : std::string("(no sample)")) +
               ", not the last one applied (" + std::to_string(wrong.sequence - 1) +
               "): nothing is applied on an error");
    }
    std::ostringstream evidence;
    evidence << kCommandCount << " zero-force commands answered in order, sample_sequence +1, "
             << period_steps << " of " << kCommandCount - 1 << " clock steps one period";
    if (host.version() >= 2) {
        evidence << ", " << counts.applied_reported << " acknowledgements, none contradictory";
    }
    evidence << "; command_gap flagged; wrong axes refused (wrong_axes), nothing applied";
    return verdict(kCommands, f, evidence.str());
}

CheckResult check_timing(ConformHost& host, const proto::Identity& identity) {
    Finding f;
    std::string why;
    if (!host.open_long_session(why)) {
        f.fail(why);
        return verdict(kTiming, f, "");
    }
    proto::ReplyTracker tracker;
    tracker.start(host.session(), host.version());
    const int exchanges = host.options().timing_exchanges;
    const double period_us = identity.period_us;
    std::vector<double> steps_us, round_trips_us, delays_periods;
    // The sample each command was computed from (its time), by sequence: the loop delay of
    // 5.7 is from that sample to the command taking effect.
    std::vector<std::uint64_t> based_on(static_cast<std::size_t>(exchanges) + 2, 0);
    std::uint64_t last_time_us = 0;
    bool have_time = false;
    int unanswered = 0;
    for (int i = 0; i < exchanges; ++i) {
        const proto::ForceCommand command = host.command(true);
        tracker.command_sent(command.sequence);
        if (command.sequence < based_on.size()) based_on[command.sequence] = last_time_us;
        const std::int64_t sent_ns = servo::monotonic_now_ns();
        host.send(command);
        const std::optional<proto::Message> reply = host.receive_for(host.session());
        const auto* sample = as<proto::EncoderSample>(reply);
        if (sample == nullptr) {
            ++unanswered;
            continue;
        }
        round_trips_us.push_back(1e-3 * static_cast<double>(servo::monotonic_now_ns() - sent_ns));
        if (have_time) steps_us.push_back(static_cast<double>(sample->time_us - last_time_us));
        const proto::ReplyTracker::Result result = tracker.check(*sample);
        if (result.applied == proto::ReplyTracker::Applied::reported &&
            result.applied_sequence < based_on.size() && result.applied_sequence > 1 &&
            based_on[result.applied_sequence] != 0) {
            delays_periods.push_back(
                static_cast<double>(result.applied_time_us - based_on[result.applied_sequence]) /
                period_us);
        }
        last_time_us = sample->time_us;
        have_time = true;
    }
    if (unanswered > 0) {
        f.fail(std::to_string(unanswered) + " of " + std::to_string(exchanges) +
               " commands got no sample (5.2: every command answered within the period)");
    }
    const double step_p50 = servo::quantile(steps_us, 0.5);
    if (std::abs(step_p50 - period_us) > 0.05 * period_us) {
        f.fail("the device's clock advanced a median " + number(step_p50, 6) +
               " us between samples one command apart; its period is " + number(period_us) +
               " us (5.2: one exchange per period)");
    }
    const double rtt_p99 = servo::quantile(round_trips_us, 0.99);
    if (host.device_paces()) {
        // 5.8: every answer at a period boundary of the device's own clock (a host that was
        // late for one gets the next: a step of two periods is the host's, not the device's).
        std::size_t off_grid = 0;
        for (const double step : steps_us) {
            const double periods = step / period_us;
            off_grid += std::abs(periods - std::round(periods)) * period_us > 2.0;
        }
        if (off_grid > 0) {
            f.fail(std::to_string(off_grid) +
                   " samples were not a whole number of periods after "
                   "the one before (5.8: a device that paces answers at its period boundaries)");
        }
    } else if (!host.options().lockstep && rtt_p99 > period_us) {
        f.fail("the answer took " + number(rtt_p99, 4) +
               " us at the 99th percentile, more than "
               "the " +
               number(period_us, 4) + " us period (5.2: within the period)");
    }
    std::ostringstream evidence;
    evidence << exchanges - unanswered << " of " << exchanges
             << " commands answered; the device's clock p50 " << number(step_p50, 6) << " us apart";
    if (host.options().lockstep) {
        evidence << "; round trips not judged (lockstep)";
    } else {
        evidence << "; round trip p50 " << number(servo::quantile(round_trips_us, 0.5), 4)
                 << " us, p99 " << number(rtt_p99, 4) << " us"
                 << (host.device_paces() ? " (the device paces: not judged, its grid is)" : "");
    }
    if (!delays_periods.empty()) {
        evidence << "; loop delay p50 " << number(servo::quantile(delays_periods, 0.5)) << ", p99 "
                 << number(servo::quantile(delays_periods, 0.99)) << " periods";
    }
    return verdict(kTiming, f, evidence.str());
}

CheckResult check_frame_errors(ConformHost& host) {
    Finding f;
    std::string why;
    if (!host.open_long_session(why)) {
        f.fail(why);
        return verdict(kFrameErrors, f, "");
    }
    const std::vector<std::byte> poll = encoded(host.poll());
    struct Case {
        const char* what;
        std::vector<std::byte> bytes;
    };
    std::vector<Case> cases;
    cases.push_back({"a poll with a bad CRC", poll});
    cases.back().bytes.back() ^= std::byte{0x5A};
    cases.push_back({"a truncated poll", {poll.begin(), poll.begin() + 9}});
    cases.push_back({"a poll with a bad magic (its CRC good)", poll});
    cases.back().bytes[proto::kOffsetMagic] = std::byte{0x49};
    fix_crc(cases.back().bytes);
    cases.push_back({"a poll whose payload_size is longer than the frame", poll});
    cases.back().bytes[proto::kOffsetPayloadSize] = std::byte{20};
    fix_crc(cases.back().bytes);
    cases.push_back({"16 bytes of garbage", std::vector<std::byte>(16, std::byte{0xA5})});
    for (const Case& c : cases) {
        host.send_raw(c.bytes);
        if (!host.silent()) {
            f.fail(std::string(c.what) +
                   " was answered (3.4: frame-level errors are dropped in "
                   "silence)");
        }
    }
    host.send(host.poll());
    const std::optional<proto::Message> last = host.receive_for(host.session());
    if (as<proto::EncoderSample>(last) == nullptr) {
        f.fail("after the damaged frames a poll of the session got no sample");
    }
    return verdict(kFrameErrors, f,
                   "a bad CRC, a truncated frame, a bad magic, a payload_size past the frame and "
                   "garbage dropped in silence; the session answered after them");
}

CheckResult check_message_errors(ConformHost& host, const proto::Identity& identity) {
    Finding f;
    std::string why;
    if (!host.open_long_session(why)) {
        f.fail(why);
        return verdict(kMessageErrors, f, "");
    }
    host.send(host.command(true));
    const std::uint32_t applied = host.last_sequence();
    (void)host.receive_for(host.session());
    const auto header = [&](std::uint8_t type, std::uint8_t payload_size) {
        proto::FrameHeader h;
        h.version = host.version();
        h.type = static_cast<proto::MessageType>(type);
        h.payload_size = payload_size;
        h.session = host.session();
        return h;
    };
    struct Case {
        const char* what;
        std::vector<std::byte> bytes;
        proto::ErrorCode code;
    };
    std::vector<Case> cases;
    cases.push_back(
        {"a frame of type 0x42", raw_frame(header(0x42, 0), {}), proto::ErrorCode::unknown_type});
    const std::vector<std::byte> sample_payload(proto::sample_payload_size(identity.axes));
    cases.push_back(
        {"a sample (device-to-host type) sent to the device",
         raw_frame(header(0x83, static_cast<std::uint8_t>(sample_payload.size())), sample_payload),
         proto::ErrorCode::unexpected_type});
    const std::vector<std::byte> four(4);
    cases.push_back({"a poll with a 4-byte payload", raw_frame(header(0x04, 4), four),
                     proto::ErrorCode::bad_length});
    std::vector<std::byte> reserved = encoded(host.command(true));
    reserved[proto::kHeaderSize + 4] |= std::byte{0x80};  // flags bit 7: reserved
    fix_crc(reserved);
    cases.push_back(
        {"a command with reserved flag bit 7 set", reserved, proto::ErrorCode::bad_field});
    for (const Case& c : cases) {
        host.send_raw(c.bytes);
        const std::optional<proto::Message> reply = host.receive_for(host.session());
        if (as_error(reply, c.code) == nullptr) {
            f.fail(std::string(c.what) + " answered with " + host.describe(reply) + " (" +
                   std::string(proto::to_string(c.code)) + " expected)");
        }
    }
    host.send(host.poll());
    const std::optional<proto::Message> sample_reply = host.receive_for(host.session());
    const auto* sample = as<proto::EncoderSample>(sample_reply);
    if (sample == nullptr || sample->command_sequence != applied) {
        f.fail("after the refused frames the sample does not name the last command applied (" +
               std::to_string(applied) + "): nothing is applied on an error (4.10)");
    }
    return verdict(kMessageErrors, f,
                   "unknown_type, unexpected_type, bad_length and bad_field as 3.4 orders them; "
                   "nothing applied");
}

CheckResult check_watchdog(ConformHost& host, const proto::Identity& identity) {
    Finding f;
    std::string why;
    const std::uint32_t timeout_us = host.options().watchdog_timeout_us;
    if (!host.open_session(timeout_us, why)) {
        f.fail(why);
        return verdict(kWatchdog, f, "");
    }
    host.send(host.command(true));
    const std::optional<proto::Message> armed_reply = host.receive_for(host.session());
    const auto* armed = as<proto::EncoderSample>(armed_reply);
    if (armed == nullptr || armed->faults != 0) {
        f.fail("the command that arms the watchdog was not answered with a fault-free sample");
        return verdict(kWatchdog, f, "");
    }
    const std::uint64_t armed_us = armed->time_us;
    const std::uint64_t period_us = identity.period_us;
    // Polls only (they do not feed it) until well past the timeout, in the device's time.
    std::optional<std::uint64_t> tripped_us;
    const std::uint64_t give_up_us = timeout_us + 5 * period_us;
    for (std::uint64_t polls = 0; polls < 2 * (give_up_us / period_us) + 10; ++polls) {
        host.send(host.poll());
        const std::optional<proto::Message> sample_reply = host.receive_for(host.session());
        const auto* sample = as<proto::EncoderSample>(sample_reply);
        if (sample == nullptr) continue;
        if ((sample->faults & proto::kDeviceFaultWatchdog) != 0) {
            tripped_us = sample->time_us - armed_us;
            break;
        }
        if (sample->time_us - armed_us > give_up_us) break;
    }
    if (!tripped_us) {
        f.fail("no watchdog fault " + std::to_string(give_up_us / 1000) +
               " ms after the last command (timeout " + std::to_string(timeout_us / 1000) +
               " ms): the force would stay on with the host gone (5.4)");
        return verdict(kWatchdog, f, "");
    }
    if (*tripped_us + period_us < timeout_us || *tripped_us > timeout_us + 2 * period_us) {
        f.fail("the watchdog fault showed " + number(1e-3 * static_cast<double>(*tripped_us)) +
               " ms after the last command; the timeout is " + number(1e-3 * timeout_us) +
               " ms (5.4: at the timeout, within the sampling of two periods)");
    }
    // 5.5: clear_faults is honoured only with enable clear.
    host.send(host.command(true, proto::kCommandClearFaults));
    const std::optional<proto::Message> kept_reply = host.receive_for(host.session());
    const auto* kept = as<proto::EncoderSample>(kept_reply);
    if (kept == nullptr || (kept->faults & proto::kDeviceFaultWatchdog) == 0) {
        f.fail(
            "clear_faults with enable set cleared the watchdog fault (5.5: only with enable "
            "clear)");
    }
    host.send(host.command(false, proto::kCommandClearFaults));
    const std::optional<proto::Message> cleared_reply = host.receive_for(host.session());
    const auto* cleared = as<proto::EncoderSample>(cleared_reply);
    if (cleared == nullptr || cleared->faults != 0) {
        f.fail("clear_faults with enable clear did not clear the watchdog fault (5.5)");
    }
    return verdict(kWatchdog, f,
                   "watchdog fault " + number(1e-3 * static_cast<double>(*tripped_us)) +
                       " ms after the last command (timeout " + number(1e-3 * timeout_us) +
                       " ms); clear_faults ignored with enable set, honoured with it clear");
}

}  // namespace hapticd::device::conform
