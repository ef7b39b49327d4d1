// ProtocolDevice: the open protocol (docs/protocol.md section 5) over any FrameLink.
#include "hapticd/device/link/protocol_device.hpp"

#include <sys/random.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "hapticd/device/protocol/servo_convert.hpp"

namespace hapticd::device::link {
namespace {

namespace proto = hapticd::device::protocol;
using servo::kStatusDisconnected;
using servo::kStatusDropped;

constexpr int kHelloAttempts = 3;  // section 5.1, step 3
constexpr std::int64_t kLockstepReplyTimeoutNs = 1'000'000'000;
constexpr double kRealtimeReplyFraction = 0.3;  // of a period: leaves 70 % for the tick
// A device that paces the loop answers at its next period boundary: up to a period after the
// command, plus the reply's time on the link (docs/protocol.md 5.8).
constexpr double kPacedReplyPeriods = 1.5;
constexpr std::int64_t kByeTimeoutNs = 50'000'000;
// 5.3, "Out of step": reads in a row that the device answered only with samples behind the
// host's count before the session is given up.
constexpr int kOutOfStepReads = 3;

std::uint32_t random_session() {
    std::uint32_t session = 0;
    while (session == 0) {
        if (getrandom(&session, sizeof session, 0) != static_cast<ssize_t>(sizeof session)) {
            session = static_cast<std::uint32_t>(
                std::chrono::steady_clock::now().time_since_epoch().count());
        }
    }
    return session;
}

std::string quoted(std::string_view text) { return "\"" + std::string(text) + "\""; }

/// A frame of `M` for `session` arrived: the handshake's waits.
template <typename M>
bool is_reply(const proto::Message& message, std::uint32_t session) {
    const auto* reply = std::get_if<M>(&message);
    return reply != nullptr && reply->session == session;
}

}  // namespace

ProtocolDevice::ProtocolDevice(std::string plugin, MakeLink make_link)
    : plugin_(std::move(plugin)), make_link_(std::move(make_link)) {}

ProtocolDevice::~ProtocolDevice() { close(); }

ProtocolDevice::Configured ProtocolDevice::configure(const DeviceConfig& config,
                                                     const std::string& plugin,
                                                     const MakeLink& make_link) {
    if (config.axes < 1 || config.axes > kMaxAxes) {
        throw input::ConfigError(
            config.source + ": " +
            input::out_of_range("device.axes", config.axes, "1.." + std::to_string(kMaxAxes)));
    }
    PluginTable table(config, plugin, "docs/transport-" + plugin + ".md");
    TableReader& reader = table.reader();
    Configured configured;
    configured.settings = read_protocol_settings(reader, config);
    configured.link = make_link(reader, LinkContext{config, configured.settings});
    reader.finish();
    return configured;
}

void ProtocolDevice::check_config(const DeviceConfig& config, const std::string& plugin,
                                  const MakeLink& make_link) {
    (void)configure(config, plugin, make_link);  // the link is made, never opened
}

void ProtocolDevice::open(const DeviceConfig& config) {
    close();
    config_ = config;
    Configured configured = configure(config, plugin_, make_link_);
    settings_ = configured.settings;
    link_ = std::move(configured.link);

    const double period_ns = 1e9 / config.rate_hz;
    reply_timeout_ns_ =
        settings_.reply_timeout_us > 0 ? std::int64_t{settings_.reply_timeout_us} * 1000
        : config.lockstep              ? kLockstepReplyTimeoutNs
                          : static_cast<std::int64_t>(kRealtimeReplyFraction * period_ns);
    have_identity_ = false;
    try {
        link_->open();
        handshake();
    } catch (...) {
        link_->close();
        throw;
    }
    identity_ = pending_identity_;
    have_identity_ = true;

    info_ = DeviceInfo{};
    info_.axes = identity_.axes;
    info_.counts_per_meter = identity_.counts_per_meter;
    info_.force_limit_n = proto::force_from_micronewtons(identity_.force_limit_un);
    // Lockstep: each command is one virtual period. A device that says it paces the loop
    // (version 3) answers each command at its own period boundary: the loop runs on its
    // samples, and waits up to kPacedReplyPeriods for each.
    info_.paces_loop = config.lockstep || identity_.paced();
    if (identity_.paced() && !config.lockstep && settings_.reply_timeout_us == 0) {
        reply_timeout_ns_ = static_cast<std::int64_t>(kPacedReplyPeriods * period_ns);
    }
    info_.lockstep = config.lockstep;
    info_.name = plugin_;
    info_.serial = std::string(identity_.serial_number());
    info_.samples_at_read = false;  // the device latches when it answers a command
    info_.protocol_version = version_;
    write_calls_ = 0;

    stop_.store(false);
    state_.store(LinkState::connected, std::memory_order_release);
    if (settings_.reconnect) reconnect_thread_ = std::thread([this] { reconnect_loop(); });
}

DeviceInfo ProtocolDevice::info() const { return info_; }

void ProtocolDevice::check_identity(const proto::Identity& identity) const {
    const std::string where = link_->describe();
    const std::string serial(identity.serial_number());
    if (!settings_.serial_number.empty() && serial != settings_.serial_number) {
        throw std::runtime_error("wrong device: " + where + " has serial number " + quoted(serial) +
                                 ", but " + config_.source + ": device." + plugin_ +
                                 ".serial_number = " + quoted(settings_.serial_number));
    }
    if (have_identity_) {
        if (serial != identity_.serial_number() || identity.axes != identity_.axes ||
            identity.counts_per_meter != identity_.counts_per_meter ||
            identity.paced() != identity_.paced()) {
            throw std::runtime_error("wrong device: " + where + " answered as serial number " +
                                     quoted(serial) + ", not the device this run started with (" +
                                     quoted(identity_.serial_number()) + "); not adopted");
        }
    }
    if (identity.axes != config_.axes) {
        throw std::runtime_error(config_.source +
                                 ": device.axes = " + std::to_string(config_.axes) +
                                 " does not match the device: " + where + " reports " +
                                 std::to_string(identity.axes) + " axes");
    }
    const auto period_us = static_cast<std::uint32_t>(std::lround(1e6 / config_.rate_hz));
    if (identity.period_us != period_us) {
        throw std::runtime_error(config_.source +
                                 ": servo.rate_hz = " + std::to_string(config_.rate_hz) +
                                 " does not match the device: " + where + " runs at a period of " +
                                 std::to_string(identity.period_us) + " us (" +
                                 std::to_string(1e6 / identity.period_us) + " Hz)");
    }
}

void ProtocolDevice::handshake() {
    link_->discard_input();
    const std::string where = link_->describe();
    const std::uint32_t session = random_session();
    const std::int64_t timeout_ns = std::int64_t{settings_.handshake_timeout_us} * 1000;

    // Waits for the reply `accept` recognises; throws on an error message for this session.
    auto await = [&](auto accept, const char* what) -> proto::Message {
        const std::int64_t deadline = monotonic_now_ns() + timeout_ns;
        for (;;) {
            std::size_t size = 0;
            const LinkResult result = link_->receive(rx_, size, deadline);
            if (result == LinkResult::timeout) return proto::Message{proto::Poll{}};
            if (result == LinkResult::disconnected) {
                throw std::runtime_error(where + " went away while waiting for " + what);
            }
            if (result != LinkResult::ok) continue;
            proto::Message message;
            const proto::Error decoded =
                proto::decode(std::span<const std::byte>(rx_.data(), size), message);
            // An identity of this session that does not decode is the device's answer, with
            // a field its maker must fix: say which, rather than wait for one that decodes.
            if (const auto* identity = std::get_if<proto::Identity>(&message);
                decoded == proto::Error::bad_field && identity != nullptr &&
                identity->session == session) {
                throw std::runtime_error(where + " sent an identity whose " +
                                         proto::out_of_range_field(*identity) +
                                         " (docs/protocol.md 4.2)");
            }
            if (decoded != proto::Error::none) continue;
            if (accept(message)) return message;
            if (const auto* error = std::get_if<proto::ErrorReport>(&message);
                error != nullptr && error->session == session) {
                throw std::runtime_error(where + " refused the " + what +
                                         " request: " + std::string(proto::to_string(error->code)) +
                                         " (detail " + std::to_string(error->detail) +
                                         "; docs/protocol.md 4.10)");
            }
        }
    };
    auto send = [&](const auto& message, const char* what) {
        const proto::Encoded encoded = proto::encode(message, tx_);
        if (!encoded.ok() ||
            link_->send(std::span<const std::byte>(tx_.data(), encoded.size)) != LinkResult::ok) {
            throw std::runtime_error("could not send " + std::string(what) + " to " + where);
        }
    };

    // 5.1 steps 2-3: hello until the identity of this session comes back.
    bool identified = false;
    for (int attempt = 0; attempt < kHelloAttempts && !identified; ++attempt) {
        send(proto::Hello{session, proto::kMinVersion, proto::kMaxVersion}, "hello");
        const proto::Message reply =
            await([&](const proto::Message& m) { return is_reply<proto::Identity>(m, session); },
                  "hello");
        if (const auto* identity = std::get_if<proto::Identity>(&reply)) {
            pending_identity_ = *identity;
            identified = true;
        }
    }
    // 3.2: the identity's header carries the chosen version; the session speaks it.
    const std::uint8_t version = pending_identity_.version;
    if (!identified) {
        throw std::runtime_error("no identity from " + where + " after " +
                                 std::to_string(kHelloAttempts) + " hello messages " +
                                 std::to_string(settings_.handshake_timeout_us / 1000) +
                                 " ms apart: is it a hapticd protocol device (on a serial line: at "
                                 "the right baud rate)? "
                                 "(docs/protocol.md 5.1)");
    }
    check_identity(pending_identity_);  // 5.1 step 4

    // Step 5: the watchdog.
    send(proto::Configure{session, settings_.watchdog_us, version}, "configure");
    const proto::Message ack =
        await([&](const proto::Message& m) { return is_reply<proto::ConfigureAck>(m, session); },
              "configure");
    if (!std::holds_alternative<proto::ConfigureAck>(ack)) {
        throw std::runtime_error(where + " did not acknowledge configure (watchdog " +
                                 std::to_string(settings_.watchdog_us) + " us)");
    }

    // Step 6: the first sample; it seeds the reply tracker.
    tracker_.start(session, version);
    session_ = session;
    version_ = version;
    command_sequence_ = 0;
    send(proto::Poll{session, version}, "poll");
    const proto::Message first =
        await([&](const proto::Message& m) { return is_reply<proto::EncoderSample>(m, session); },
              "poll");
    const auto* sample = std::get_if<proto::EncoderSample>(&first);
    if (sample == nullptr) throw std::runtime_error(where + " did not answer the first poll");
    (void)tracker_.check(*sample);
    tracker_counts_.store(tracker_.counters());
    device_faulted_ = sample->faults != 0;
    reply_outstanding_ = false;
    behind_reads_ = 0;
}

bool ProtocolDevice::adopt_if_ready() noexcept {
    if (state_.load(std::memory_order_acquire) != LinkState::ready) return false;
    state_.store(LinkState::connected, std::memory_order_release);
    return true;
}

IoResult ProtocolDevice::lost() noexcept {
    counts_.disconnects.fetch_add(1, std::memory_order_relaxed);
    // From here the reconnect thread owns the link (if there is one).
    state_.store(LinkState::lost, std::memory_order_release);
    return IoResult::disconnected;
}

IoResult ProtocolDevice::send_frame(std::span<const std::byte> frame) noexcept {
    switch (link_->send(frame)) {
        case LinkResult::ok:
            return IoResult::ok;
        case LinkResult::disconnected:
            return lost();
        case LinkResult::timeout:
        case LinkResult::error:
            break;
    }
    return IoResult::error;
}

void ProtocolDevice::pass_on_applied(const proto::ReplyTracker::Result& verdict,
                                     Sample& sample) const noexcept {
    using Applied = proto::ReplyTracker::Applied;
    switch (verdict.applied) {
        case Applied::unsupported:
            sample.applied = servo::AppliedReport::unsupported;
            return;
        case Applied::none:
            sample.applied = servo::AppliedReport::none;
            return;
        case Applied::bad_command:
            sample.applied = servo::AppliedReport::bad_command;
            return;
        case Applied::bad_time:
            sample.applied = servo::AppliedReport::bad_time;
            return;
        case Applied::reported:
            break;
    }
    // The tracker vouched that it is one of this session's commands, at most 254 behind the
    // last: the ring still holds the write() call that sent it.
    sample.applied = servo::AppliedReport::reported;
    sample.applied_write = write_of_sequence_[verdict.applied_sequence % write_of_sequence_.size()];
    sample.applied_time_s = proto::time_from_microseconds(verdict.applied_time_us);
}

IoResult ProtocolDevice::read(Sample& sample) noexcept {
    sample = Sample{};
    if (state_.load(std::memory_order_acquire) != LinkState::connected && !adopt_if_ready()) {
        sample.status = kStatusDisconnected | kStatusDropped;
        return IoResult::disconnected;
    }
    if (!reply_outstanding_) {
        const proto::Encoded poll = proto::encode(proto::Poll{session_, version_}, tx_);
        const IoResult sent = send_frame(std::span<const std::byte>(tx_.data(), poll.size));
        if (sent != IoResult::ok) {
            sample.status =
                (sent == IoResult::disconnected ? kStatusDisconnected : 0u) | kStatusDropped;
            return sent;
        }
        counts_.polls_sent.fetch_add(1, std::memory_order_relaxed);
        reply_outstanding_ = true;
    }

    const std::int64_t deadline = monotonic_now_ns() + reply_timeout_ns_;
    bool behind = false;  // the device answered this session's last request from behind
    for (;;) {
        std::size_t size = 0;
        const LinkResult result = link_->receive(rx_, size, deadline);
        if (result != LinkResult::ok) {
            reply_outstanding_ = false;  // the next read polls again
            sample.status = kStatusDropped;
            if (result == LinkResult::timeout) {
                counts_.reply_timeouts.fetch_add(1, std::memory_order_relaxed);
                behind_reads_ = behind ? behind_reads_ + 1 : 0;
                if (behind_reads_ >= kOutOfStepReads) {
                    // 5.3, "Out of step": no sample of this session can be taken again.
                    counts_.out_of_step.fetch_add(1, std::memory_order_relaxed);
                    sample.status |= kStatusDisconnected;
                    return lost();
                }
                return IoResult::timeout;
            }
            if (result == LinkResult::disconnected) {
                sample.status |= kStatusDisconnected;
                return lost();
            }
            return IoResult::error;
        }
        proto::Message message;
        if (proto::decode(std::span<const std::byte>(rx_.data(), size), message) !=
            proto::Error::none) {
            counts_.bad_frames.fetch_add(1, std::memory_order_relaxed);
            continue;  // 5.3: a broken frame is the same as none
        }
        if (const auto* reply = std::get_if<proto::EncoderSample>(&message)) {
            const proto::ReplyTracker::Result verdict = tracker_.check(*reply);
            tracker_counts_.store(tracker_.counters());
            // A repeat echoes the last request: the device is answering, from behind.
            if (verdict.verdict == proto::ReplyTracker::Verdict::duplicate) behind = true;
            if (verdict.verdict != proto::ReplyTracker::Verdict::accept) continue;
            behind_reads_ = 0;
            sample = proto::to_servo_sample(*reply, verdict.sequence, verdict.host_status);
            pass_on_applied(verdict, sample);
            device_faulted_ = reply->faults != 0;
            reply_outstanding_ = false;
            counts_.samples_accepted.fetch_add(1, std::memory_order_relaxed);
            return IoResult::ok;
        }
        if (const auto* error = std::get_if<proto::ErrorReport>(&message);
            error != nullptr && error->session == session_) {
            counts_.device_errors.fetch_add(1, std::memory_order_relaxed);
            reply_outstanding_ = false;
            sample.status = kStatusDropped;
            // The device no longer knows this session (it restarted): a new handshake.
            if (error->code == proto::ErrorCode::no_session ||
                error->code == proto::ErrorCode::wrong_session) {
                sample.status |= kStatusDisconnected;
                return lost();
            }
            return IoResult::error;  // the request was refused: nothing was applied
        }
        // Anything else (another session's frames, stray identities) is not for this read.
    }
}

IoResult ProtocolDevice::write(const Command& command) noexcept {
    if (state_.load(std::memory_order_acquire) != LinkState::connected) {
        return IoResult::disconnected;
    }
    ++write_calls_;
    proto::ForceCommand frame;
    const bool finite =
        proto::make_force_command(command, config_.axes, session_, command_sequence_ + 1, frame);
    frame.version = version_;
    // 5.5: latched device faults are cleared only by a disabled command. When the servo
    // enables force again (its operator reset its own latch), this period holds zero force
    // and clears the device; the next command applies force.
    if (device_faulted_ && frame.enable()) {
        frame.flags = proto::kCommandClearFaults;
        frame.force_un.fill(0);
    }
    const proto::Encoded encoded = proto::encode(frame, tx_);
    const IoResult sent = send_frame(std::span<const std::byte>(tx_.data(), encoded.size));
    if (sent != IoResult::ok) return sent;
    ++command_sequence_;
    write_of_sequence_[command_sequence_ % write_of_sequence_.size()] = write_calls_;
    tracker_.command_sent(command_sequence_);
    reply_outstanding_ = true;
    counts_.commands_sent.fetch_add(1, std::memory_order_relaxed);
    return finite ? IoResult::ok : IoResult::error;
}

void ProtocolDevice::reconnect_loop() {
    const auto slice = std::chrono::milliseconds(5);
    std::string last_message;
    while (!stop_.load()) {
        if (state_.load(std::memory_order_acquire) != LinkState::lost) {
            std::this_thread::sleep_for(slice);
            continue;
        }
        link_->close();
        try {
            link_->open();
            handshake();
            counts_.reconnects.fetch_add(1, std::memory_order_relaxed);
            std::fprintf(stderr, "hapticd: device %s: reconnected: %s\n", plugin_.c_str(),
                         link_->describe().c_str());
            last_message.clear();
            state_.store(LinkState::ready, std::memory_order_release);
            continue;
        } catch (const std::exception& e) {
            link_->close();
            const std::string message = e.what();
            if (message.rfind("wrong device", 0) == 0) {
                counts_.refused_devices.fetch_add(1, std::memory_order_relaxed);
            }
            if (message != last_message) {  // say each new reason once, not every attempt
                std::fprintf(stderr, "hapticd: device %s: waiting for the device: %s\n",
                             plugin_.c_str(), message.c_str());
                last_message = message;
            }
        }
        const auto interval = std::chrono::microseconds(settings_.reconnect_interval_us);
        for (auto waited = std::chrono::microseconds(0); waited < interval && !stop_.load();
             waited += slice) {
            std::this_thread::sleep_for(slice);
        }
    }
}

void ProtocolDevice::close() noexcept {
    stop_.store(true);
    if (reconnect_thread_.joinable()) reconnect_thread_.join();
    const LinkState state = state_.load();
    if (link_ == nullptr) {
        state_.store(LinkState::closed);
        return;
    }
    if (state == LinkState::connected || state == LinkState::ready) {
        // Zero force, then end the session (5.1); the device's watchdog covers a lost bye.
        state_.store(LinkState::connected);
        (void)write(Command{});
        state_.store(LinkState::closed);
        const proto::Encoded bye = proto::encode(proto::Bye{session_, version_}, tx_);
        if (link_->send(std::span<const std::byte>(tx_.data(), bye.size)) == LinkResult::ok) {
            const std::int64_t deadline = monotonic_now_ns() + kByeTimeoutNs;
            std::size_t size = 0;
            while (link_->receive(rx_, size, deadline) == LinkResult::ok) {
                proto::ByeAck ack;
                if (proto::decode(std::span<const std::byte>(rx_.data(), size), ack) ==
                    proto::Error::none) {
                    break;
                }
            }
        }
    }
    state_.store(LinkState::closed);
    link_->close();
}

ProtocolCounters ProtocolDevice::counters() const noexcept {
    ProtocolCounters c;
    c.commands_sent = counts_.commands_sent.load(std::memory_order_relaxed);
    c.polls_sent = counts_.polls_sent.load(std::memory_order_relaxed);
    c.samples_accepted = counts_.samples_accepted.load(std::memory_order_relaxed);
    c.reply_timeouts = counts_.reply_timeouts.load(std::memory_order_relaxed);
    c.bad_frames = counts_.bad_frames.load(std::memory_order_relaxed);
    c.device_errors = counts_.device_errors.load(std::memory_order_relaxed);
    c.disconnects = counts_.disconnects.load(std::memory_order_relaxed);
    c.out_of_step = counts_.out_of_step.load(std::memory_order_relaxed);
    c.reconnects = counts_.reconnects.load(std::memory_order_relaxed);
    c.refused_devices = counts_.refused_devices.load(std::memory_order_relaxed);
    const proto::ReplyTracker::Counters t = tracker_counts_.load();
    c.wrong_session = t.wrong_session;
    c.unexpected = t.unexpected;
    c.late = t.late;
    c.duplicate = t.duplicate;
    c.missed_samples = t.missed;
    c.applied_reported = t.applied_reported;
    c.applied_bad_command = t.applied_bad_command;
    c.applied_bad_time = t.applied_bad_time;
    return c;
}

// link_ is set by open() alone, before any other thread may call this, and never reset
// after; the counts it reads are relaxed atomics (here and in every FrameLink) and a
// seqlock whose reader retries rather than waits for the tick.
LinkQuality ProtocolDevice::link_quality() const noexcept {
    const ProtocolCounters p = counters();
    LinkQuality q;
    q.counted = true;
    q.bad_frames = p.bad_frames;
    q.reply_timeouts = p.reply_timeouts;
    q.missed_samples = p.missed_samples;
    q.late = p.late;
    q.duplicate = p.duplicate;
    q.device_errors = p.device_errors;
    q.disconnects = p.disconnects;
    q.reconnects = p.reconnects;
    q.wrong_session = p.wrong_session;
    q.unexpected = p.unexpected;
    q.out_of_step = p.out_of_step;
    if (link_ != nullptr) {
        const LinkCounters l = link_->counters();
        q.frames_sent = l.frames_sent;
        q.frames_received = l.frames_received;
        q.bad_frames += l.framing_errors;
        q.transfer_errors = l.send_errors + l.receive_errors;
    }
    return q;
}

}  // namespace hapticd::device::link
