#include "hapticd/servo/link_recovery.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapticd::servo {

namespace {

std::uint64_t to_ticks(double seconds, double rate_hz) {
    return static_cast<std::uint64_t>(std::max<long long>(1, std::llround(seconds * rate_hz)));
}

}  // namespace

bool LinkRecoverySettings::is_valid(std::string* error) const {
    if (!kSettleRange.contains(settle_s)) {
        return input::invalid(
            error, input::out_of_range("link_recovery.settle_s", settle_s, kSettleRange));
    }
    if (!(timeout_s == 0.0 || (timeout_s > settle_s && kTimeoutRange.contains(timeout_s)))) {
        return input::invalid(
            error, input::out_of_range("link_recovery.timeout_s", timeout_s,
                                       "0 (wait for ever) or > settle_s = " +
                                           input::format_number(settle_s) + " and <= 3600 (s)"));
    }
    return true;
}

void LinkRecoverySettings::validate() const {
    std::string error;
    if (!is_valid(&error)) throw std::invalid_argument(error);
}

LinkRecovery::LinkRecovery(const LinkRecoverySettings& settings, double rate_hz)
    : enabled_(settings.enabled) {
    settings.validate();
    if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
        throw std::invalid_argument("link recovery: rate_hz must be a finite number > 0");
    }
    settle_ticks_ = to_ticks(settings.settle_s, rate_hz);
    timeout_periods_ = settings.timeout_s > 0.0 ? to_ticks(settings.timeout_s, rate_hz) : 0;
}

void LinkRecovery::reset() noexcept {
    good_ticks_ = 0;
    latched_periods_ = 0;
    gave_up_ = false;
}

LinkAction LinkRecovery::update(std::uint32_t latched, bool good_tick,
                                std::uint64_t periods) noexcept {
    if (!enabled_) return LinkAction::none;
    if (gave_up_) return LinkAction::give_up;
    if (latched == 0u) {
        good_ticks_ = 0;
        latched_periods_ = 0;
        return LinkAction::none;
    }
    if (!only_link_faults(latched)) {
        // Not ours to clear: an operator must look (the run stops or waits for a reset).
        good_ticks_ = 0;
        return LinkAction::none;
    }
    good_ticks_ = good_tick ? good_ticks_ + 1 : 0;
    latched_periods_ += periods;
    if (good_ticks_ >= settle_ticks_) {
        reset();
        return LinkAction::recover;
    }
    if (timeout_periods_ != 0 && latched_periods_ >= timeout_periods_) {
        gave_up_ = true;
        return LinkAction::give_up;
    }
    return LinkAction::none;
}

}  // namespace hapticd::servo
