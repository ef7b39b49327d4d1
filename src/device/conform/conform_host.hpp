// The tester's side of the link (conformance.hpp): requests out, answers in, with the
// deadlines and the pacing of docs/protocol.md 5.2, and the bookkeeping every check needs
// (the session, its version, the next command sequence). Internal to the conformance tester.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hapticd/device/conform/conformance.hpp"
#include "hapticd/device/link/frame_link.hpp"
#include "hapticd/device/protocol/messages.hpp"

namespace hapticd::device::conform {

/// A check's verdict so far: the first failure wins.
struct Finding {
    bool failed = false;
    std::string detail;
    void fail(std::string why) {
        if (!failed) detail = std::move(why);
        failed = true;
    }
};

class ConformHost {
  public:
    ConformHost(link::FrameLink& link, const ConformOptions& options);

    const ConformOptions& options() const noexcept { return options_; }
    double period_s() const noexcept { return 1.0 / options_.rate_hz; }
    std::uint32_t period_us() const noexcept;

    /// A new random session id (never 0, never the last one).
    std::uint32_t new_session();
    /// hello(session, min, max) -> the identity of that session; nullopt on silence, an
    /// error or anything else (`why` says which). Sets session() and version() on success.
    std::optional<protocol::Identity> hello(std::uint32_t session, std::uint8_t min_version,
                                            std::uint8_t max_version, std::string& why);
    /// hello at the widest range, then configure(watchdog): a session ready for commands.
    /// false with `why` otherwise.
    bool open_session(std::uint32_t watchdog_us, std::string& why);
    /// open_session() with the longest watchdog the device takes (1 s, or the nearest it
    /// names when it refuses that): for checks that are not about the watchdog, so that a
    /// host that stalls does not trip it.
    bool open_long_session(std::string& why);

    std::uint32_t session() const noexcept { return session_; }
    std::uint8_t version() const noexcept { return version_; }
    std::uint8_t axes() const noexcept { return axes_; }
    /// The session's device paces the loop (version 3, 5.8): the host does not wait for a
    /// period boundary, it sends as soon as it has the sample before.
    bool device_paces() const noexcept { return device_paces_; }
    std::uint32_t next_sequence() noexcept { return ++sequence_; }
    std::uint32_t last_sequence() const noexcept { return sequence_; }
    /// Skips `n` sequence numbers (the command gap check).
    void skip_sequences(std::uint32_t n) noexcept { sequence_ += n; }

    /// A zero-force command of this session: enabled or not, with `flags` added.
    protocol::ForceCommand command(bool enable, std::uint8_t flags = 0) noexcept;
    protocol::Poll poll() const noexcept { return {session_, version_}; }

    /// Encodes and sends one message; false if it does not encode or the link refuses it.
    template <typename M>
    bool send(const M& message) {
        std::vector<std::byte> out(protocol::kMaxFrameSize);
        const protocol::Encoded encoded = protocol::encode(message, out);
        if (!encoded.ok()) return false;
        out.resize(encoded.size);
        return send_raw(out);
    }
    /// Sends bytes as one frame of the transport (whatever they hold), paced.
    bool send_raw(std::span<const std::byte> frame);

    /// The next frame that decodes into a Message within the reply timeout (undecodable
    /// frames are counted and skipped); nullopt on silence.
    std::optional<protocol::Message> receive();
    /// The next message of `session` (another session's are skipped); nullopt on silence.
    std::optional<protocol::Message> receive_for(std::uint32_t session);
    /// Waits the reply timeout: true if nothing at all came (not even a frame that does not
    /// decode).
    bool silent();
    /// Drops whatever is in flight: waits a little and discards.
    void drain();

    /// Frames that came and did not decode, so far.
    std::uint64_t undecodable() const noexcept { return undecodable_; }

    /// One line for a message: "error wrong_session (detail 0)", "sample seq 3", ...
    static std::string describe(const protocol::Message& message);
    /// describe(), or "nothing within 100 ms".
    std::string describe(const std::optional<protocol::Message>& message) const;

  private:
    /// Real time: waits for the next period boundary after the last request.
    void pace();

    link::FrameLink& link_;
    ConformOptions options_;
    std::uint32_t session_ = 0;
    std::uint8_t version_ = protocol::kProtocolVersion1;
    std::uint8_t axes_ = 1;
    bool device_paces_ = false;
    std::uint32_t sequence_ = 0;
    std::uint32_t last_session_ = 0;
    std::int64_t next_send_ns_ = 0;
    std::uint64_t undecodable_ = 0;
    std::vector<std::byte> rx_;
};

/// The message as T if it is one (and of `session`, when given).
template <typename T>
const T* as(const std::optional<protocol::Message>& message) {
    return message ? std::get_if<T>(&*message) : nullptr;
}

/// Not for a temporary: the pointer would dangle.
template <typename T>
const T* as(const std::optional<protocol::Message>&& message) = delete;

/// An error message with `code`, or null.
const protocol::ErrorReport* as_error(const std::optional<protocol::Message>& message,
                                      protocol::ErrorCode code);

}  // namespace hapticd::device::conform
