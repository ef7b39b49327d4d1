// The reference device (docs/protocol.md sections 5 and 7).
#include "hapticd/device/protocol/device_emulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "hapticd/device/protocol/servo_convert.hpp"
#include "hapticd/device/protocol/status_map.hpp"
#include "hapticd/device/protocol/transport.hpp"
#include "hapticd/input/range.hpp"

namespace hapticd::device::protocol {
namespace {

std::uint32_t version_range_detail(std::uint8_t min_version, std::uint8_t max_version) noexcept {
    return static_cast<std::uint32_t>(min_version) | (static_cast<std::uint32_t>(max_version) << 8);
}

/// Section 3.4: the error code a device answers a message-level decode error with.
ErrorCode error_code_for(Error error) noexcept {
    switch (error) {
        case Error::bad_version:
            return ErrorCode::bad_version;
        case Error::unknown_type:
            return ErrorCode::unknown_type;
        case Error::bad_payload_size:
            return ErrorCode::bad_length;
        default:
            return ErrorCode::bad_field;
    }
}

}  // namespace

DeviceEmulator::DeviceEmulator(const EmulatorConfig& config)
    : min_version_(config.min_version),
      max_version_(config.max_version),
      default_watchdog_timeout_us_(config.default_watchdog_timeout_us),
      max_watchdog_timeout_us_(config.max_watchdog_timeout_us),
      poll_advances_period_(config.poll_advances_period),
      force_limit_un_(0) {
    sim::SimConfig sim_config = config.sim;
    sim_config.clock = sim::SimClock::lockstep;
    if (sim_config.axes < 1 || sim_config.axes > kMaxProtocolAxes) {
        input::reject_out_of_range("device emulator: sim.axes", sim_config.axes, "1..3");
    }
    if (!identity_.set_serial_number(config.serial_number)) {
        input::reject_out_of_range("device emulator: serial_number",
                                   "\"" + config.serial_number + "\"",
                                   "1 to 16 printable ASCII characters");
    }
    const double force_limit_un = std::round(sim_config.force_limit_n * 1e6);
    if (!(force_limit_un >= 1.0) ||
        force_limit_un > static_cast<double>(std::numeric_limits<std::int32_t>::max())) {
        input::reject_out_of_range("device emulator: sim.force_limit_n", sim_config.force_limit_n,
                                   "1e-6 to 2147.483647 (N, the wire's int32 micronewtons)");
    }
    const double period_us = 1e6 / sim_config.rate_hz;
    if (!std::isfinite(period_us) || std::abs(period_us - std::round(period_us)) > 1e-6 ||
        period_us < 1.0) {
        input::reject_out_of_range("device emulator: sim.rate_hz", sim_config.rate_hz,
                                   "a rate of a whole number of microseconds per period");
    }
    if (min_version_ < 1 || max_version_ < min_version_) {
        input::reject_out_of_range(
            "device emulator: versions",
            "[" + std::to_string(min_version_) + ", " + std::to_string(max_version_) + "]",
            "[min, max] with 1 <= min <= max");
    }
    const auto period = static_cast<std::uint32_t>(std::round(period_us));
    if (max_watchdog_timeout_us_ > kMaxWatchdogTimeoutUs || max_watchdog_timeout_us_ < 2 * period ||
        default_watchdog_timeout_us_ < 2 * period ||
        default_watchdog_timeout_us_ > max_watchdog_timeout_us_) {
        input::reject_out_of_range("device emulator: watchdog timeouts",
                                   "default " + std::to_string(default_watchdog_timeout_us_) +
                                       " us, max " + std::to_string(max_watchdog_timeout_us_) +
                                       " us",
                                   "2 periods <= default <= max <= 1 s");
    }
    force_limit_un_ = static_cast<std::int32_t>(force_limit_un);

    sim_.open(sim_config);
    identity_.axes = static_cast<std::uint8_t>(sim_config.axes);
    identity_.force_limit_un = force_limit_un_;
    identity_.counts_per_meter = sim_config.counts_per_meter;
    identity_.period_us = period;
    identity_.watchdog_timeout_us = default_watchdog_timeout_us_;
    identity_.firmware_version = config.firmware_version;
    watchdog_timeout_us_ = default_watchdog_timeout_us_;
}

std::uint64_t DeviceEmulator::time_us() const noexcept {
    return static_cast<std::uint64_t>(std::llround(sim_.time_s() * 1e6));
}

std::array<double, kMaxProtocolAxes> DeviceEmulator::output_force_n() const noexcept {
    std::array<double, kMaxProtocolAxes> force_n{};
    if (!held_.enable) return force_n;
    const double limit_n = sim_.config().force_limit_n;
    for (int i = 0; i < identity_.axes; ++i) {
        force_n[i] = std::clamp(held_.force_n[i], -limit_n, limit_n);
    }
    return force_n;
}

// ---- time: section 5.2 (ZOH) and 5.4 (watchdog) ----

void DeviceEmulator::zero_force() noexcept { held_ = servo::Command{}; }

void DeviceEmulator::close_session() noexcept {
    zero_force();
    session_open_ = false;
    command_seen_ = false;
    current_tag_ = 0;
}

void DeviceEmulator::check_watchdog() noexcept {
    if (!session_open_ || !command_seen_ || (latched_faults_ & kDeviceFaultWatchdog) != 0u) return;
    if (time_us() - last_command_us_ >= watchdog_timeout_us_) {
        latched_faults_ |= kDeviceFaultWatchdog;
        zero_force();
        ++counters_.watchdog_trips;
    }
}

void DeviceEmulator::step_period() noexcept {
    if (gone_) return;
    // Lockstep: one period, ZOH; the command lands sim.delay_s after it arrived.
    if (sim_.write_tagged(held_, current_tag_) == servo::IoResult::disconnected) {
        gone_ = true;
        zero_force();
        return;
    }
    check_watchdog();
}

void DeviceEmulator::advance_period() noexcept {
    if (gone_) return;
    if (faults_.device_faults != 0u) {
        latched_faults_ |= faults_.device_faults;
        faults_.device_faults = 0;
        zero_force();
    }
    step_period();
    ++periods_since_command_;
}

// ---- requests ----

DeviceEmulator::Reply DeviceEmulator::handle(std::span<const std::byte> request,
                                             std::span<std::byte> out) noexcept {
    ++counters_.requests;
    Outbox outbox{out, {}};
    if (gone_) return outbox.reply;
    if (faults_.stall > 0) {
        // Hung: the request is lost, the clock runs on.
        --faults_.stall;
        advance_period();
        return outbox.reply;
    }
    if (faults_.device_faults != 0u) {
        latched_faults_ |= faults_.device_faults;
        faults_.device_faults = 0;
        zero_force();
    }
    if (delayed_size_ > 0) {
        // The reply held back last time goes out first: the host sees it late.
        const std::array<std::byte, kMaxFrameSize> delayed = delayed_;
        const std::size_t size = delayed_size_;
        delayed_size_ = 0;
        emit(std::span<const std::byte>(delayed).first(size), outbox);
    }
    dispatch(request, outbox);
    return outbox.reply;
}

void DeviceEmulator::dispatch(std::span<const std::byte> request, Outbox& outbox) noexcept {
    // Section 3.4: frame-level errors are dropped silently; message-level ones are answered.
    FrameView frame;
    const Error frame_error = decode_frame(request, frame);
    if (is_frame_error(frame_error)) {
        ++counters_.dropped_requests;
        return;
    }
    if (frame_error != Error::none) {
        const std::uint32_t detail = frame_error == Error::bad_version
                                         ? version_range_detail(min_version_, max_version_)
                                         : 0u;
        send_error(frame.header, error_code_for(frame_error), detail, outbox);
        return;
    }
    if (!is_host_to_device(frame.header.type)) {
        send_error(frame.header, ErrorCode::unexpected_type, 0, outbox);
        return;
    }
    Message message;
    if (const Error error = decode_payload(frame, message); error != Error::none) {
        send_error(frame.header, error_code_for(error), 0, outbox);
        return;
    }
    if (const auto* hello = std::get_if<Hello>(&message)) {
        on_hello(frame, *hello, outbox);
        return;
    }
    // Section 5.1: everything but hello needs the current session.
    if (!session_open_) {
        send_error(frame.header, ErrorCode::no_session, 0, outbox);
        return;
    }
    if (frame.header.session != session_) {
        send_error(frame.header, ErrorCode::wrong_session, 0, outbox);
        return;
    }
    // Section 3.2: the session speaks the version its hello chose, and nothing else.
    if (frame.header.version != version_) {
        send_error(frame.header, ErrorCode::bad_version,
                   version_range_detail(min_version_, max_version_), outbox);
        return;
    }
    if (const auto* configure = std::get_if<Configure>(&message)) {
        on_configure(*configure, outbox);
    } else if (const auto* command = std::get_if<ForceCommand>(&message)) {
        on_command(*command, outbox);
    } else if (std::holds_alternative<Poll>(message)) {
        on_poll(outbox);
    } else if (const auto* bye = std::get_if<Bye>(&message)) {
        on_bye(*bye, outbox);
    }
}

void DeviceEmulator::on_hello(const FrameView& frame, const Hello& hello, Outbox& outbox) noexcept {
    // Section 5.1: any hello ends the current session (zero force) before anything else.
    close_session();
    const std::uint8_t low = std::max({hello.min_version, min_version_, kMinVersion});
    const std::uint8_t high = std::min({hello.max_version, max_version_, kMaxVersion});
    if (high < low) {
        send_error(frame.header, ErrorCode::unsupported_version,
                   version_range_detail(min_version_, max_version_), outbox);
        return;
    }
    session_open_ = true;
    session_ = hello.session;
    version_ = high;
    ++session_epoch_;
    current_tag_ = 0;
    commands_in_session_ = 0;
    watchdog_timeout_us_ = default_watchdog_timeout_us_;
    last_command_sequence_ = 0;
    periods_since_command_ = 0;
    last_clamped_ = false;
    sample_sequence_ = 0;
    latched_faults_ &= static_cast<std::uint16_t>(~kDeviceFaultWatchdog);  // that host is gone
    identity_.session = session_;
    identity_.watchdog_timeout_us = watchdog_timeout_us_;
    identity_.version = version_;
    send(identity_, outbox);
}

void DeviceEmulator::on_configure(const Configure& configure, Outbox& outbox) noexcept {
    // Section 5.4: [2 periods, the device's maximum]; detail = the nearest allowed value.
    const std::uint32_t min_us = 2 * identity_.period_us;
    if (configure.watchdog_timeout_us < min_us ||
        configure.watchdog_timeout_us > max_watchdog_timeout_us_) {
        FrameHeader header;
        header.type = Configure::kType;
        header.session = configure.session;
        send_error(header, ErrorCode::out_of_range,
                   std::clamp(configure.watchdog_timeout_us, min_us, max_watchdog_timeout_us_),
                   outbox);
        return;
    }
    watchdog_timeout_us_ = configure.watchdog_timeout_us;
    identity_.watchdog_timeout_us = watchdog_timeout_us_;
    ConfigureAck ack;
    ack.session = session_;
    ack.watchdog_timeout_us = watchdog_timeout_us_;
    ack.version = version_;
    send(ack, outbox);
}

void DeviceEmulator::on_command(const ForceCommand& command, Outbox& outbox) noexcept {
    if (command.axes != identity_.axes) {
        FrameHeader header;
        header.type = ForceCommand::kType;
        header.session = command.session;
        send_error(header, ErrorCode::wrong_axes, identity_.axes, outbox);
        return;
    }
    // Section 5.2: how this command arrived.
    std::uint16_t status = 0;
    if (command_seen_) {
        if (command.sequence != last_command_sequence_ + 1) status |= kSampleCommandGap;
        if (periods_since_command_ > 0) status |= kSampleCommandLate;
    }
    // Section 5.5: faults clear only with enable off.
    if ((command.flags & kCommandClearFaults) != 0u && !command.enable()) latched_faults_ = 0;

    zero_force();
    last_clamped_ = false;
    if (command.enable() && latched_faults_ == 0u) {
        held_ = to_servo_command(command);
        for (int i = 0; i < command.axes; ++i) {
            const std::int64_t magnitude_un = std::abs(std::int64_t{command.force_un[i]});
            if (magnitude_un > force_limit_un_) last_clamped_ = true;
        }
    }
    command_seen_ = true;
    last_command_sequence_ = command.sequence;
    last_command_us_ = time_us();
    current_tag_ = (std::uint64_t{session_epoch_} << 32) | command.sequence;
    ++commands_in_session_;
    periods_since_command_ = 0;
    ++counters_.commands_applied;

    step_period();  // the command is held for one period (ZOH), then the counts are latched
    if (gone_) return;
    send_sample(status, outbox);
}

void DeviceEmulator::on_poll(Outbox& outbox) noexcept {
    if (poll_advances_period_) {
        advance_period();
        if (gone_) return;
    }
    send_sample(0, outbox);
}

void DeviceEmulator::on_bye(const Bye& bye, Outbox& outbox) noexcept {
    close_session();
    ByeAck ack;
    ack.session = bye.session;
    ack.version = version_;
    send(ack, outbox);
}

// ---- replies ----

void DeviceEmulator::send_error(const FrameHeader& request, ErrorCode code, std::uint32_t detail,
                                Outbox& outbox) noexcept {
    ErrorReport report;
    report.session = request.session;
    report.code = code;
    report.request_type = static_cast<std::uint8_t>(request.type);
    report.detail = detail;
    ++counters_.errors_sent;
    send(report, outbox);
}

void DeviceEmulator::send_sample(std::uint16_t status, Outbox& outbox) noexcept {
    servo::Sample sample;
    const servo::IoResult result = sim_.read(sample);
    if (result == servo::IoResult::disconnected) {
        gone_ = true;
        zero_force();
        return;
    }
    EncoderSample message;
    message.session = session_;
    message.version = version_;
    message.command_sequence = command_seen_ ? last_command_sequence_ : 0;
    sample_sequence_ += faults_.sequence_gap;
    faults_.sequence_gap = 0;
    message.sample_sequence = sample_sequence_++;
    message.time_us = time_us();
    message.axes = identity_.axes;
    for (int i = 0; i < identity_.axes; ++i) message.counts[i] = sample.encoder_counts[i];
    message.status = static_cast<std::uint16_t>(status | sample_status_from_servo(sample.status));
    if (held_.enable) message.status |= kSampleForceActive;
    if (last_clamped_) message.status |= kSampleForceClamped;
    message.faults = latched_faults_;
    if (version_ >= kProtocolVersion2) fill_applied(sample, message);
    damage_sample(message);
    if (result == servo::IoResult::timeout) return;  // the simulated device dropped it
    ++counters_.samples_sent;
    if ((sample.status & servo::kStatusLate) != 0u) ++faults_.delay;  // a late sample
    send(message, outbox);
}

void DeviceEmulator::fill_applied(const servo::Sample& sample,
                                  EncoderSample& message) const noexcept {
    // What landed last, by the simulated device's own account; a command of this session
    // (an older session's might still land after a hello: it is not this host's to hear of).
    if (!command_seen_ || sample.applied != servo::AppliedReport::reported ||
        (sample.applied_write >> 32) != session_epoch_) {
        return;  // kAppliedLagNone, kAppliedAgeUnknown
    }
    const auto applied = static_cast<std::uint32_t>(sample.applied_write & 0xFFFFFFFFu);
    const std::uint32_t lag = message.command_sequence - applied;
    const auto applied_us = static_cast<std::uint64_t>(std::llround(sample.applied_time_s * 1e6));
    if (lag > kMaxAppliedLag || applied_us > message.time_us) return;
    message.applied_lag = static_cast<std::uint8_t>(lag);
    const std::uint64_t age_us = message.time_us - applied_us;
    message.applied_age_us =
        age_us >= kAppliedAgeUnknown ? kAppliedAgeUnknown : static_cast<std::uint16_t>(age_us);
}

void DeviceEmulator::damage_sample(EncoderSample& message) noexcept {
    const bool v2 = message.version >= kProtocolVersion2;
    if (v2 && faults_.applied_unsent > 0) {
        --faults_.applied_unsent;
        // One before the session's first command (or, before any, the "command 0"): a
        // command this host never sent.
        message.applied_lag = static_cast<std::uint8_t>(
            command_seen_ ? std::min<std::uint64_t>(kMaxAppliedLag, commands_in_session_) : 0);
        message.applied_age_us = 0;
    }
    if (v2 && faults_.applied_early_us > 0 && message.applied_age_us != kAppliedAgeUnknown) {
        const std::uint64_t age = std::min<std::uint64_t>(
            {std::uint64_t{message.applied_age_us} + faults_.applied_early_us,
             kAppliedAgeUnknown - 1u, message.time_us});
        message.applied_age_us = static_cast<std::uint16_t>(age);
        faults_.applied_early_us = 0;
    }
    if (faults_.sequence_ahead > 0) {
        message.sample_sequence += faults_.sequence_ahead;
        faults_.sequence_ahead = 0;
    }
    if (faults_.clock_back_us > 0) {
        message.time_us -= std::min<std::uint64_t>(message.time_us, faults_.clock_back_us);
        if (message.applied_age_us != kAppliedAgeUnknown &&
            message.applied_age_us > message.time_us) {
            message.applied_age_us = static_cast<std::uint16_t>(message.time_us);
        }
        faults_.clock_back_us = 0;
    }
}

template <typename M>
void DeviceEmulator::send(M message, Outbox& outbox) noexcept {
    if (faults_.wrong_session > 0) {
        --faults_.wrong_session;
        message.session ^= 0xA5A5A5A5u;
    }
    std::array<std::byte, kMaxFrameSize> frame{};
    const Encoded encoded = encode(message, frame);
    if (!encoded.ok()) return;  // not reachable: the emulator builds valid messages
    std::size_t size = encoded.size;
    if (faults_.corrupt_crc > 0) {
        --faults_.corrupt_crc;
        frame[size - 1] ^= std::byte{0x01};
    }
    if (faults_.truncate > 0) {
        --faults_.truncate;
        size /= 2;
    }
    if (faults_.drop > 0) {
        --faults_.drop;
        return;
    }
    if (faults_.delay > 0 && delayed_size_ == 0) {
        --faults_.delay;
        delayed_ = frame;
        delayed_size_ = size;
        return;
    }
    emit(std::span<const std::byte>(frame).first(size), outbox);
}

void DeviceEmulator::emit(std::span<const std::byte> frame, Outbox& outbox) noexcept {
    Reply& reply = outbox.reply;
    if (reply.frames == kMaxReplyFrames || outbox.out.size() < reply.size + frame.size()) return;
    std::copy(frame.begin(), frame.end(),
              outbox.out.begin() + static_cast<std::ptrdiff_t>(reply.size));
    reply.frame_sizes[reply.frames++] = frame.size();
    reply.size += frame.size();
}

// ---- transport adapters: section 6 ----

std::size_t DeviceEmulator::handle_stream(std::span<const std::byte> bytes,
                                          std::span<std::byte> out) noexcept {
    std::size_t written = 0;
    for (const std::byte b : bytes) {
        // Garbage, overflows and broken COBS are counted by the framer and never answered.
        if (stream_.push(b) != StreamDecoder::Event::frame) continue;
        std::array<std::byte, kMaxReplySize> replies{};
        const Reply reply = handle(stream_.frame(), replies);
        std::size_t offset = 0;
        for (std::size_t i = 0; i < reply.frames; ++i) {
            const auto frame =
                std::span<const std::byte>(replies).subspan(offset, reply.frame_sizes[i]);
            offset += reply.frame_sizes[i];
            const Encoded encoded = encode_stream(frame, out.subspan(written));
            if (encoded.ok()) written += encoded.size;
        }
    }
    return written;
}

std::size_t DeviceEmulator::handle_hid_report(std::span<const std::byte> report,
                                              std::span<std::byte> out) noexcept {
    std::span<const std::byte> frame;
    if (hid::unwrap_report(hid::kOutputReportId, report, frame) != Error::none) {
        ++counters_.requests;
        ++counters_.dropped_requests;
        return 0;
    }
    std::array<std::byte, kMaxReplySize> replies{};
    const Reply reply = handle(frame, replies);
    std::size_t written = 0;
    std::size_t offset = 0;
    for (std::size_t i = 0; i < reply.frames; ++i) {
        const auto reply_frame =
            std::span<const std::byte>(replies).subspan(offset, reply.frame_sizes[i]);
        offset += reply.frame_sizes[i];
        const Encoded encoded =
            hid::wrap_report(hid::kInputReportId, reply_frame, out.subspan(written));
        if (encoded.ok()) written += encoded.size;
    }
    return written;
}

}  // namespace hapticd::device::protocol
