#include "conform_host.hpp"

#include <sys/random.h>

#include <chrono>
#include <cmath>
#include <sstream>

#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::device::conform {

namespace proto = protocol;

ConformHost::ConformHost(link::FrameLink& link, const ConformOptions& options)
    : link_(link), options_(options), rx_(proto::kMaxFrameSize) {}

std::uint32_t ConformHost::period_us() const noexcept {
    return static_cast<std::uint32_t>(std::lround(1e6 / options_.rate_hz));
}

std::uint32_t ConformHost::new_session() {
    std::uint32_t session = 0;
    while (session == 0 || session == last_session_) {
        if (getrandom(&session, sizeof session, 0) != static_cast<ssize_t>(sizeof session)) {
            session = static_cast<std::uint32_t>(
                std::chrono::steady_clock::now().time_since_epoch().count());
        }
    }
    last_session_ = session;
    return session;
}

void ConformHost::pace() {
    if (options_.lockstep || device_paces_) return;
    const std::int64_t now = servo::monotonic_now_ns();
    if (now < next_send_ns_) servo::sleep_until_monotonic_ns(next_send_ns_);
    next_send_ns_ =
        std::max(now, next_send_ns_) + static_cast<std::int64_t>(std::llround(1e9 * period_s()));
}

bool ConformHost::send_raw(std::span<const std::byte> frame) {
    pace();
    return link_.send(frame) == link::LinkResult::ok;
}

std::optional<proto::Message> ConformHost::receive() {
    const std::int64_t deadline = servo::monotonic_now_ns() + options_.reply_timeout_ns;
    for (;;) {
        std::size_t size = 0;
        const link::LinkResult result = link_.receive(rx_, size, deadline);
        if (result == link::LinkResult::timeout || result == link::LinkResult::disconnected) {
            return std::nullopt;
        }
        if (result != link::LinkResult::ok) continue;
        proto::Message message;
        if (proto::decode(std::span<const std::byte>(rx_.data(), size), message) ==
            proto::Error::none) {
            return message;
        }
        ++undecodable_;
    }
}

std::optional<proto::Message> ConformHost::receive_for(std::uint32_t session) {
    const std::int64_t deadline = servo::monotonic_now_ns() + options_.reply_timeout_ns;
    while (servo::monotonic_now_ns() < deadline) {
        std::optional<proto::Message> message = receive();
        if (!message) return std::nullopt;
        if (proto::session_of(*message) == session) return message;
    }
    return std::nullopt;
}

bool ConformHost::silent() {
    const std::int64_t deadline = servo::monotonic_now_ns() + options_.reply_timeout_ns;
    std::size_t size = 0;
    for (;;) {
        const link::LinkResult result = link_.receive(rx_, size, deadline);
        if (result == link::LinkResult::ok) return false;
        if (result == link::LinkResult::timeout || result == link::LinkResult::disconnected) {
            return true;
        }
    }
}

void ConformHost::drain() {
    std::size_t size = 0;
    const std::int64_t deadline = servo::monotonic_now_ns() + options_.reply_timeout_ns / 4;
    while (link_.receive(rx_, size, deadline) == link::LinkResult::ok) {
    }
    link_.discard_input();
}

std::optional<proto::Identity> ConformHost::hello(std::uint32_t session, std::uint8_t min_version,
                                                  std::uint8_t max_version, std::string& why) {
    drain();
    if (!send(proto::Hello{session, min_version, max_version})) {
        why = "the link refused the hello";
        return std::nullopt;
    }
    const std::optional<proto::Message> reply = receive_for(session);
    if (const auto* identity = as<proto::Identity>(reply)) {
        session_ = session;
        version_ = identity->version;
        axes_ = identity->axes;
        device_paces_ = identity->paced();
        sequence_ = 0;
        return *identity;
    }
    why = "hello(session " + std::to_string(session) + ", versions " + std::to_string(min_version) +
          ".." + std::to_string(max_version) + ") answered with " + describe(reply);
    return std::nullopt;
}

bool ConformHost::open_session(std::uint32_t watchdog_us, std::string& why) {
    if (!hello(new_session(), proto::kMinVersion, proto::kMaxVersion, why)) return false;
    if (!send(proto::Configure{session_, watchdog_us, version_})) {
        why = "the link refused the configure";
        return false;
    }
    const std::optional<proto::Message> reply = receive_for(session_);
    if (as<proto::ConfigureAck>(reply) == nullptr) {
        why = "configure(watchdog " + std::to_string(watchdog_us) + " us) answered with " +
              describe(reply);
        return false;
    }
    return true;
}

bool ConformHost::open_long_session(std::string& why) {
    if (!hello(new_session(), proto::kMinVersion, proto::kMaxVersion, why)) return false;
    std::uint32_t watchdog_us = proto::kMaxWatchdogTimeoutUs;
    for (int attempt = 0; attempt < 2; ++attempt) {
        send(proto::Configure{session_, watchdog_us, version_});
        const std::optional<proto::Message> reply = receive_for(session_);
        if (as<proto::ConfigureAck>(reply) != nullptr) return true;
        const auto* refused = as_error(reply, proto::ErrorCode::out_of_range);
        if (refused == nullptr || attempt == 1) {
            why = "configure(watchdog " + std::to_string(watchdog_us) + " us) answered with " +
                  describe(reply);
            return false;
        }
        watchdog_us = refused->detail;  // the nearest it takes
    }
    return false;
}

proto::ForceCommand ConformHost::command(bool enable, std::uint8_t flags) noexcept {
    proto::ForceCommand c;
    c.session = session_;
    c.version = version_;
    c.sequence = next_sequence();
    c.flags = static_cast<std::uint8_t>((enable ? proto::kCommandEnable : 0) | flags);
    c.axes = axes_;
    return c;
}

std::string ConformHost::describe(const proto::Message& message) {
    std::ostringstream out;
    out << proto::to_string(proto::type_of(message));
    if (const auto* e = std::get_if<proto::ErrorReport>(&message)) {
        out << ' ' << proto::to_string(e->code) << " (detail " << e->detail << ')';
    } else if (const auto* s = std::get_if<proto::EncoderSample>(&message)) {
        out << " (command " << s->command_sequence << ", sample " << s->sample_sequence
            << ", faults 0x" << std::hex << s->faults << ')';
    }
    return out.str();
}

std::string ConformHost::describe(const std::optional<proto::Message>& message) const {
    if (message) return describe(*message);
    return "nothing within " + std::to_string(options_.reply_timeout_ns / 1'000'000) + " ms";
}

const proto::ErrorReport* as_error(const std::optional<proto::Message>& message,
                                   proto::ErrorCode code) {
    const auto* error = as<proto::ErrorReport>(message);
    return error != nullptr && error->code == code ? error : nullptr;
}

}  // namespace hapticd::device::conform
