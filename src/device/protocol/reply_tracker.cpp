// Host-side reply checks (docs/protocol.md section 5.3).
#include "hapticd/device/protocol/reply_tracker.hpp"

#include "hapticd/servo/io.hpp"

namespace hapticd::device::protocol {

void ReplyTracker::start(std::uint32_t session) noexcept {
    session_ = session;
    last_command_ = 0;
    command_sent_ = false;
    last_sample_ = 0;
    last_sequence_ = 0;
    have_sample_ = false;
    late_pending_ = false;
}

void ReplyTracker::command_sent(std::uint32_t sequence) noexcept {
    last_command_ = sequence;
    command_sent_ = true;
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
    return result;
}

bool serial_matches(const Identity& identity, std::string_view expected) noexcept {
    return identity.serial_number() == expected;
}

}  // namespace hapticd::device::protocol
