#include "hapticd/device/sim/sim_device.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <limits>

namespace hapticd::device::sim {
namespace {

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();

std::int64_t monotonic_ns() noexcept {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

void sleep_s(double duration_s) noexcept {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(duration_s);
    ts.tv_nsec = static_cast<long>((duration_s - static_cast<double>(ts.tv_sec)) * 1e9);
    while (clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, &ts) == EINTR) {
    }
}

}  // namespace

void SimDevice::open(const DeviceConfig& config) { open(parse_sim_config(config)); }

void SimDevice::open(const SimConfig& config) {
    close();
    config_ = config;
    const double period_s = config_.period_s();
    for (int i = 0; i < config_.axes; ++i) {
        plants_[i].configure(config_.mass_kg, config_.damping_n_s_per_m, config_.coulomb_n,
                             config_.human[i], period_s, config_.initial_position_m[i]);
    }
    faults_.configure(config_.faults, period_s);
    held_force_n_.fill(0.0);
    units_ = 0;
    samples_produced_ = 0;
    previous_sample_time_s_ = kMinusInfinity;
    for (int i = 0; i < config_.axes; ++i) last_fresh_counts_[i] = encoder_counts(i);
    open_time_ns_ = monotonic_ns();
    open_ = true;
}

DeviceInfo SimDevice::info() const {
    DeviceInfo info;
    info.axes = config_.axes;
    info.counts_per_meter = config_.counts_per_meter;
    info.force_limit_n = config_.force_limit_n;
    info.lockstep = config_.clock == SimClock::lockstep;
    info.paces_loop = info.lockstep;
    info.name = "sim";
    info.serial = "sim-0";
    return info;
}

double SimDevice::units_to_s(std::uint64_t units) const noexcept {
    // Whole periods and the fraction separately, so lockstep times are exactly n T.
    const double period_s = config_.period_s();
    return static_cast<double>(units >> kFractionBits) * period_s +
           std::ldexp(static_cast<double>(units & (kUnitsPerPeriod - 1)), -kFractionBits) *
               period_s;
}

double SimDevice::time_s() const noexcept { return units_to_s(units_); }

std::uint64_t SimDevice::now_units() const noexcept {
    const double elapsed_s = static_cast<double>(monotonic_ns() - open_time_ns_) * 1e-9;
    const double units =
        std::floor(elapsed_s * config_.rate_hz * static_cast<double>(kUnitsPerPeriod));
    return units > 0.0 ? static_cast<std::uint64_t>(units) : 0;
}

void SimDevice::advance_to(std::uint64_t units) noexcept {
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
    sample.encoder_counts.fill(0);
    if (verdict.disconnected) {
        held_force_n_.fill(0.0);  // the device's watchdog: no host, no force
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
    if (verdict.late && !lockstep) sleep_s(faults_.late_by_s());
    return verdict.dropped ? IoResult::timeout : IoResult::ok;
}

IoResult SimDevice::write(const Command& command) noexcept {
    if (!open_) return IoResult::disconnected;
    const bool lockstep = config_.clock == SimClock::lockstep;
    if (!lockstep) advance_to(now_units());  // the old force held until now
    const bool disconnected = faults_.disconnected(time_s());
    bool finite = true;
    for (int i = 0; i < config_.axes; ++i) {
        const double f = command.force_n[i];
        finite = finite && std::isfinite(f);
        held_force_n_[i] = command.enable && std::isfinite(f)
                               ? std::clamp(f, -config_.force_limit_n, config_.force_limit_n)
                               : 0.0;
    }
    if (!finite || disconnected) held_force_n_.fill(0.0);
    if (lockstep) advance_to(units_ + kUnitsPerPeriod);  // exactly one period under this force
    if (disconnected) return IoResult::disconnected;
    return finite ? IoResult::ok : IoResult::error;
}

void SimDevice::close() noexcept {
    held_force_n_.fill(0.0);
    open_ = false;
}

}  // namespace hapticd::device::sim
