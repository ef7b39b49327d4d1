#include "hapticd/servo/link_recovery.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace hapticd::servo {

namespace {

[[noreturn]] void reject(const char* field, double value, const char* expected) {
    std::ostringstream message;
    message << "servo config: link_recovery." << field << " must be " << expected << ", got "
            << value;
    throw std::invalid_argument(message.str());
}

std::uint64_t to_ticks(double seconds, double rate_hz) {
    return static_cast<std::uint64_t>(std::max<long long>(1, std::llround(seconds * rate_hz)));
}

}  // namespace

void LinkRecoverySettings::validate() const {
    if (!(settle_s > 0.0 && settle_s <= 60.0)) reject("settle_s", settle_s, "in (0, 60] s");
    if (!(timeout_s == 0.0 || (timeout_s > settle_s && timeout_s <= 3600.0))) {
        reject("timeout_s", timeout_s, "0 (wait for ever) or in (settle_s, 3600] s");
    }
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
