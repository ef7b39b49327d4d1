// The loop delay and the commands in flight (command_pipeline.hpp).
#include "hapticd/device/sim/command_pipeline.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hapticd/device/sim/axis_plant.hpp"

namespace hapticd::device::sim {

LoopDelay split_delay(double delay_s, double rate_hz) {
    double periods = delay_s * rate_hz;
    if (!std::isfinite(delay_s) || delay_s < 0.0 || !(periods < kMaxDelayPeriods)) {
        std::ostringstream s;
        s << "sim device: loop delay " << delay_s << " s at " << rate_hz << " Hz is not >= 0 and < "
          << kMaxDelayPeriods << " periods";
        throw std::invalid_argument(s.str());
    }
    const double nearest = std::round(periods);
    if (std::abs(periods - nearest) <= 1e-9) periods = nearest;
    LoopDelay delay;
    delay.whole_periods = static_cast<std::uint64_t>(std::floor(periods));
    delay.fraction = periods - std::floor(periods);
    delay.units =
        static_cast<std::uint64_t>(std::llround(periods * static_cast<double>(kUnitsPerPeriod)));
    return delay;
}

void CommandPipeline::configure(std::size_t capacity) {
    ring_.assign(capacity < 1 ? 1 : capacity, PendingCommand{});
    head_ = 0;
    size_ = 0;
}

void CommandPipeline::push(std::uint64_t due, const std::array<double, kMaxAxes>& force_n,
                           std::uint64_t tag) noexcept {
    if (ring_.empty()) return;           // not configured: a device that was never opened
    if (size_ == ring_.size()) --size_;  // full: the newest in flight is replaced
    PendingCommand& slot = ring_[(head_ + size_) % ring_.size()];
    slot.due = due;
    slot.force_n = force_n;
    slot.tag = tag;
    ++size_;
}

const PendingCommand* CommandPipeline::due(std::uint64_t now) const noexcept {
    if (size_ == 0 || ring_[head_].due > now) return nullptr;
    return &ring_[head_];
}

void CommandPipeline::pop() noexcept {
    if (size_ == 0) return;
    head_ = (head_ + 1) % ring_.size();
    --size_;
}

}  // namespace hapticd::device::sim
