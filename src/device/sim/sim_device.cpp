#include "hapticd/device/sim/sim_device.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hapticd/servo/monotonic_clock.hpp"

namespace hapticd::device::sim {
namespace {

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();
/// Realtime clock: room for this many commands in flight (a host writing more often than
/// this within one loop delay has its newest command in flight replaced, command_pipeline.hpp).
constexpr std::size_t kRealtimeCommandsInFlight = 1024;

}  // namespace

void SimDevice::open(const DeviceConfig& config) { open(parse_sim_config(config)); }

void SimDevice::open(const SimConfig& config) {
    close();
    config_ = config;
    const double period_s = config_.period_s();
    delay_ = split_delay(config_.delay_s, config_.rate_hz);
    const bool lockstep = config_.clock == SimClock::lockstep;
    for (int i = 0; i < config_.axes; ++i) {
        plants_[i].configure(config_.mass_kg, config_.damping_n_s_per_m, config_.coulomb_n,
                             config_.human[i], period_s, config_.initial_position_m[i],
                             lockstep ? delay_.fraction : 0.0);
    }
    faults_.configure(config_.faults, period_s);
    // Lockstep: F[n-q] .. F[n] are in flight after the write of tick n.
    pipeline_.configure(lockstep ? static_cast<std::size_t>(delay_.whole_periods) + 2
                                 : kRealtimeCommandsInFlight);
    held_force_n_.fill(0.0);
    units_ = 0;
    sample_units_ = 0;
    samples_produced_ = 0;
    previous_sample_time_s_ = kMinusInfinity;
    writes_ = 0;
    applied_tag_ = 0;
    applied_time_s_ = 0.0;
    for (int i = 0; i < config_.axes; ++i) last_fresh_counts_[i] = encoder_counts(i);
    open_time_ns_ = servo::monotonic_now_ns();
    open_ = true;
}

DeviceInfo SimDevice::info() const {
    DeviceInfo info;
    info.axes = config_.axes;
    info.counts_per_meter = config_.counts_per_meter;
    info.force_limit_n = config_.force_limit_n;
    info.lockstep = config_.clock == SimClock::lockstep;
    info.paces_loop = info.lockstep;
    info.samples_at_read = true;
    info.name = "sim";
    info.serial = "sim-0";
    return info;
}

double SimDevice::units_to_s(std::uint64_t units) const noexcept {
    // Periods (whole and fraction, exact in a double) divided by the rate: lockstep times
    // are the doubles nearest n/rate, which the telemetry prints as short decimals (tick 9 at
    // 1 kHz is 0.009 s, where 9 * (1/1000) is 0.009000000000000001).
    const double periods =
        static_cast<double>(units >> kFractionBits) +
        std::ldexp(static_cast<double>(units & (kUnitsPerPeriod - 1)), -kFractionBits);
    return periods / config_.rate_hz;
}

double SimDevice::time_s() const noexcept { return units_to_s(units_); }

std::uint64_t SimDevice::now_units() const noexcept {
    const double elapsed_s = static_cast<double>(servo::monotonic_now_ns() - open_time_ns_) * 1e-9;
    const double units =
        std::floor(elapsed_s * config_.rate_hz * static_cast<double>(kUnitsPerPeriod));
    return units > 0.0 ? static_cast<std::uint64_t>(units) : 0;
}

void SimDevice::advance_to(std::uint64_t units) noexcept {
    // Each command in flight lands at its own time: the held force up to it, then it.
    while (const PendingCommand* landing = pipeline_.due(units)) {
        advance_held_to(landing->due);
        held_force_n_ = landing->force_n;
        took_effect(landing->tag, units_to_s(landing->due));
        pipeline_.pop();
    }
    advance_held_to(units);
}

void SimDevice::advance_held_to(std::uint64_t units) noexcept {
    if (units <= units_) return;
    // Whole periods one at a time, so the set-point profile is sampled at least once a period.
    while (units - units_ >= kUnitsPerPeriod) {
        const double end_s = units_to_s(units_ + kUnitsPerPeriod);
        for (int i = 0; i < config_.axes; ++i) {
            plants_[i].step_period(held_force_n_[i], config_.human[i].push.set_point_m(end_s));
        }
        units_ += kUnitsPerPeriod;
    }
    if (units > units_) {
        const double end_s = units_to_s(units);
        for (int i = 0; i < config_.axes; ++i) {
            plants_[i].advance(units - units_, held_force_n_[i],
                               config_.human[i].push.set_point_m(end_s));
        }
        units_ = units;
    }
}

void SimDevice::step_lockstep_period() noexcept {
    // Period n: F[n-q-1] (held) until nT + φT, then F[n-q], the command due in period n.
    const std::uint64_t period = units_ >> kFractionBits;
    const std::array<double, kMaxAxes> lead_force_n = held_force_n_;
    if (const PendingCommand* landing = pipeline_.due(period)) {
        held_force_n_ = landing->force_n;
        took_effect(landing->tag, units_to_s(units_) + delay_.fraction * config_.period_s());
        pipeline_.pop();
    }
    const double end_s = units_to_s(units_ + kUnitsPerPeriod);
    for (int i = 0; i < config_.axes; ++i) {
        plants_[i].step_period_split(lead_force_n[i], held_force_n_[i],
                                     config_.human[i].push.set_point_m(end_s));
    }
    units_ += kUnitsPerPeriod;
}

void SimDevice::cut_force() noexcept {
    held_force_n_.fill(0.0);
    pipeline_.clear();
}

void SimDevice::took_effect(std::uint64_t tag, double time_s) noexcept {
    if (tag == applied_tag_) return;  // the same command again: it acts since its first landing
    applied_tag_ = tag;
    applied_time_s_ = time_s;
}

std::int64_t SimDevice::encoder_counts(int axis) const noexcept {
    // Quantisation: floor, like an incremental encoder whose count changes as x crosses
    // each line at k / counts_per_meter.
    const double counts = std::floor(plants_[axis].state().position_m * config_.counts_per_meter);
    constexpr double kLimit = 9.0e18;
    return static_cast<std::int64_t>(std::clamp(counts, -kLimit, kLimit));
}

IoResult SimDevice::read(Sample& sample) noexcept {
    if (!open_) {
        sample.status = servo::kStatusDisconnected;
        return IoResult::disconnected;
    }
    const bool lockstep = config_.clock == SimClock::lockstep;
    if (!lockstep) advance_to(now_units());
    sample_units_ = units_;
    const double time_s = units_to_s(units_);
    const std::uint64_t sequence = lockstep ? units_ >> kFractionBits : samples_produced_++;
    const double previous_s = lockstep
                                  ? (sequence == 0 ? kMinusInfinity : time_s - config_.period_s())
                                  : previous_sample_time_s_;
    previous_sample_time_s_ = time_s;
    const FaultVerdict verdict = faults_.evaluate(previous_s, time_s, sequence);

    sample.device_time_s = time_s;
    sample.sequence = sequence;
    sample.status = verdict.status;
    sample.applied_write = applied_tag_;
    sample.applied_time_s = applied_time_s_;
    sample.applied =
        applied_tag_ != 0 ? servo::AppliedReport::reported : servo::AppliedReport::none;
    sample.encoder_counts.fill(0);
    if (verdict.disconnected) {
        cut_force();  // the device's watchdog: no host, no force, nothing in flight lands
        return IoResult::disconnected;
    }
    const bool fresh = !verdict.stale && !verdict.dropped;
    for (int i = 0; i < config_.axes; ++i) {
        if (fresh) {
            last_fresh_counts_[i] = encoder_counts(i);
            if (i == faults_.jump_axis()) last_fresh_counts_[i] += verdict.jump_offset_counts;
        }
        sample.encoder_counts[i] = last_fresh_counts_[i];
    }
    if (verdict.late && !lockstep)
        servo::sleep_until_monotonic_ns(servo::monotonic_now_ns() +
                                        std::llround(faults_.late_by_s() * 1e9));
    return verdict.dropped ? IoResult::timeout : IoResult::ok;
}

IoResult SimDevice::write(const Command& command) noexcept {
    if (!open_) return IoResult::disconnected;
    return write_tagged(command, ++writes_);
}

IoResult SimDevice::write_tagged(const Command& command, std::uint64_t tag) noexcept {
    if (!open_) return IoResult::disconnected;
    const bool lockstep = config_.clock == SimClock::lockstep;
    if (!lockstep) advance_to(now_units());  // the old force held until now
    const bool disconnected = faults_.disconnected(time_s());
    bool finite = true;
    std::array<double, kMaxAxes> force_n{};
    for (int i = 0; i < config_.axes; ++i) {
        const double f = command.force_n[i];
        finite = finite && std::isfinite(f);
        force_n[i] = command.enable && std::isfinite(f)
                         ? std::clamp(f, -config_.force_limit_n, config_.force_limit_n)
                         : 0.0;
    }
    if (!finite || disconnected) {
        cut_force();  // refused, or no device: zero now, whatever was in flight
        if (!disconnected) took_effect(tag, time_s());  // the refusal's zero acts at once
    } else if (lockstep) {
        // Written in tick n: starts to act in period n + q, at φT into it.
        pipeline_.push((units_ >> kFractionBits) + delay_.whole_periods, force_n, tag);
    } else {
        // D after the sample it was computed from, and never before now.
        pipeline_.push(std::max(sample_units_ + delay_.units, units_), force_n, tag);
    }
    if (lockstep) {
        step_lockstep_period();  // exactly one period, the commands landing in it
    } else {
        advance_to(units_);  // lands at once when it is due now (no delay)
    }
    if (disconnected) return IoResult::disconnected;
    return finite ? IoResult::ok : IoResult::error;
}

void SimDevice::close() noexcept {
    cut_force();  // zero force, and nothing still in flight lands after the close
    open_ = false;
}

}  // namespace hapticd::device::sim
