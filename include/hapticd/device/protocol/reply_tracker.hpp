// Host side: is this sample the reply the host is waiting for? (docs/protocol.md section 5.3)
//
// A transport plugin feeds every decoded sample to ReplyTracker::check() and uses only the
// accepted ones. It finds:
//   - a frame of another session or device (the session id differs, or the sample echoes a
//     command this session never sent): ignored;
//   - a late reply (it echoes an older command than the last one sent: the answer to an
//     earlier period that missed its deadline): ignored, and kStatusLate is set on the next
//     accepted sample;
//   - a repeated or reordered sample (sample_sequence did not advance): ignored;
//   - lost samples (sample_sequence advanced by more than one): accepted, with the count of
//     missed samples; the 64-bit sequence it returns jumps by the same amount, which is how the
//     servo sees the gap (servo::Sample::sequence).
// Of an accepted version-2 sample it also checks what the device says about the command in
// effect (applied_lag, applied_age_us; section 5.3, "Acknowledgements"): it must be a command
// this session sent, never one older than the device named before, and the moment it took
// effect must neither move nor go back, nor the device's clock. A sample that fails only this
// is still accepted (its counts are as good as any); its acknowledgement is not used.
// Sequence numbers are compared in serial-number arithmetic modulo 2^32 (RFC 1982), so they
// may wrap (after 49.7 days at 1 kHz).
#pragma once

#include <cstdint>

#include "hapticd/device/protocol/messages.hpp"

namespace hapticd::device::protocol {

/// How far `to` is ahead of `from`, modulo 2^32: in [-2^31, 2^31).
constexpr std::int32_t sequence_distance(std::uint32_t from, std::uint32_t to) noexcept {
    return static_cast<std::int32_t>(to - from);
}

class ReplyTracker {
  public:
    enum class Verdict : std::uint8_t {
        accept,         ///< the awaited reply: use it
        wrong_session,  ///< another session's frame (a stale one, or another device's): ignore
        unexpected,     ///< echoes a command this session never sent: ignore (wrong device)
        late,           ///< echoes an older command: a late reply; ignore
        duplicate,      ///< sample_sequence did not advance: ignore
    };

    /// What an accepted sample says about the command in effect.
    enum class Applied : std::uint8_t {
        unsupported,  ///< version 1: nothing
        none,         ///< no command named, or its age is unknown (kAppliedAgeUnknown)
        reported,     ///< applied_sequence and applied_time_us are valid
        bad_command,  ///< names a command this session never sent, or an older one than before
        bad_time,     ///< the device's clock went backwards, or a command's moment moved back
    };

    struct Result {
        Verdict verdict = Verdict::wrong_session;
        std::uint64_t sequence = 0;     ///< accept: the unwrapped sample sequence
        std::uint32_t missed = 0;       ///< accept: samples lost since the last accepted one
        std::uint32_t host_status = 0;  ///< accept: servo bits found by the host (kStatusLate)
        Applied applied = Applied::unsupported;  ///< accept
        std::uint32_t applied_sequence = 0;      ///< reported: the command in effect
        std::uint64_t applied_time_us = 0;       ///< reported: device time it took effect, us
    };

    struct Counters {
        std::uint64_t accepted = 0;
        std::uint64_t wrong_session = 0;
        std::uint64_t unexpected = 0;
        std::uint64_t late = 0;
        std::uint64_t duplicate = 0;
        std::uint64_t missed = 0;  ///< samples lost, summed over the gaps
        std::uint64_t applied_reported = 0;
        std::uint64_t applied_bad_command = 0;  ///< acknowledgements of commands never sent
        std::uint64_t applied_bad_time = 0;     ///< device times going backwards
    };

    /// A new session (after the identity answered hello) in the negotiated `version`: forgets
    /// everything but the counters.
    void start(std::uint32_t session, std::uint8_t version = kProtocolVersion1) noexcept;

    /// The host sent the command with this sequence (call before waiting for its reply).
    void command_sent(std::uint32_t sequence) noexcept;

    /// Classifies a decoded sample. Only an accepted sample changes the state.
    Result check(const EncoderSample& sample) noexcept;

    std::uint32_t session() const noexcept { return session_; }
    std::uint8_t version() const noexcept { return version_; }
    const Counters& counters() const noexcept { return counters_; }

  private:
    /// The acknowledgement checks of an accepted sample.
    void check_applied(const EncoderSample& sample, Result& result) noexcept;

    std::uint32_t session_ = 0;
    std::uint8_t version_ = kProtocolVersion1;
    std::uint32_t last_command_ = 0;
    std::uint64_t commands_in_session_ = 0;
    bool command_sent_ = false;
    bool have_time_ = false;
    std::uint64_t last_time_us_ = 0;  ///< of the last accepted sample with a sound clock
    bool have_applied_ = false;
    std::uint32_t last_applied_ = 0;          ///< the last command reported in effect ...
    std::uint64_t last_applied_time_us_ = 0;  ///< ... and when it took effect
    std::uint32_t last_sample_ = 0;
    std::uint64_t last_sequence_ = 0;
    bool have_sample_ = false;
    bool late_pending_ = false;
    Counters counters_;
};

/// The serial number the identity reports equals `expected` (section 5.1: "the wrong device").
bool serial_matches(const Identity& identity, std::string_view expected) noexcept;

}  // namespace hapticd::device::protocol
