// Host-side reply checks (docs/protocol.md section 5.3).
#include "hapticd/device/protocol/reply_tracker.hpp"

#include "hapticd/servo/io.hpp"

namespace hapticd::device::protocol {

void ReplyTracker::start(std::uint32_t session, std::uint8_t version) noexcept {
    session_ = session;
    version_ = version;
    last_command_ = 0;
    commands_in_session_ = 0;
    command_sent_ = false;
    have_time_ = false;
    last_time_us_ = 0;
    have_applied_ = false;
    last_applied_ = 0;
    last_applied_time_us_ = 0;
    last_sample_ = 0;
    last_sequence_ = 0;
    have_sample_ = false;
    late_pending_ = false;
}

void ReplyTracker::command_sent(std::uint32_t sequence) noexcept {
    last_command_ = sequence;
    command_sent_ = true;
    ++commands_in_session_;
}

void ReplyTracker::check_applied(const EncoderSample& sample, Result& result) noexcept {
    // The device's clock first: a sample from the past says nothing about when.
    if (have_time_ && sample.time_us < last_time_us_) {
        result.applied = Applied::bad_time;
        ++counters_.applied_bad_time;
        return;
    }
    if (sample.version == kProtocolVersion1) {
        result.applied = Applied::unsupported;
        have_time_ = true;
        last_time_us_ = sample.time_us;
        return;
    }
    if (!sample.names_applied()) {
        // "No command in effect" after one was: the device forgot what it applied.
        if (have_applied_) {
            result.applied = Applied::bad_command;
            ++counters_.applied_bad_command;
            return;
        }
        result.applied = Applied::none;
        have_time_ = true;
        last_time_us_ = sample.time_us;
        return;
    }
    // The command it names: one this session sent (the accepted sample answers the last one
    // sent, so the lag counts back from it), and not older than the one it named before.
    const std::uint32_t applied = sample.applied_sequence();
    if (!command_sent_ || sample.applied_lag >= commands_in_session_ ||
        (have_applied_ && sequence_distance(last_applied_, applied) < 0)) {
        result.applied = Applied::bad_command;
        ++counters_.applied_bad_command;
        return;
    }
    if (sample.applied_age_us == kAppliedAgeUnknown) {
        result.applied = Applied::none;  // too long ago to say (the decoder checked the rest)
        have_time_ = true;
        last_time_us_ = sample.time_us;
        return;
    }
    const std::uint64_t applied_time_us = sample.time_us - sample.applied_age_us;
    if (have_applied_ && (applied == last_applied_ ? applied_time_us != last_applied_time_us_
                                                   : applied_time_us < last_applied_time_us_)) {
        // The moment a force took effect cannot move, and a later command cannot have
        // taken effect before an earlier one.
        result.applied = Applied::bad_time;
        ++counters_.applied_bad_time;
        return;
    }
    have_time_ = true;
    last_time_us_ = sample.time_us;
    have_applied_ = true;
    last_applied_ = applied;
    last_applied_time_us_ = applied_time_us;
    result.applied = Applied::reported;
    result.applied_sequence = applied;
    result.applied_time_us = applied_time_us;
    ++counters_.applied_reported;
}

ReplyTracker::Result ReplyTracker::check(const EncoderSample& sample) noexcept {
    Result result;
    if (sample.session != session_) {
        ++counters_.wrong_session;
        result.verdict = Verdict::wrong_session;
        return result;
    }
    // Which command does it answer? Before the first command the device echoes 0.
    const std::int32_t echo = command_sent_
                                  ? sequence_distance(last_command_, sample.command_sequence)
                                  : (sample.command_sequence == 0 ? 0 : 1);
    if (echo > 0) {
        ++counters_.unexpected;
        result.verdict = Verdict::unexpected;
        return result;
    }
    if (echo < 0) {
        ++counters_.late;
        late_pending_ = true;
        result.verdict = Verdict::late;
        return result;
    }
    std::int32_t advance = 1;
    if (have_sample_) {
        advance = sequence_distance(last_sample_, sample.sample_sequence);
        if (advance <= 0) {
            ++counters_.duplicate;
            result.verdict = Verdict::duplicate;
            return result;
        }
        last_sequence_ += static_cast<std::uint64_t>(advance);
    } else {
        last_sequence_ = sample.sample_sequence;
        have_sample_ = true;
    }
    last_sample_ = sample.sample_sequence;
    result.verdict = Verdict::accept;
    result.sequence = last_sequence_;
    result.missed = static_cast<std::uint32_t>(advance - 1);
    result.host_status = late_pending_ ? servo::kStatusLate : 0u;
    late_pending_ = false;
    ++counters_.accepted;
    counters_.missed += result.missed;
    check_applied(sample, result);
    return result;
}

bool serial_matches(const Identity& identity, std::string_view expected) noexcept {
    return identity.serial_number() == expected;
}

}  // namespace hapticd::device::protocol
