#include "hapticd/device/sim/fault_injector.hpp"

#include <algorithm>

#include "hapticd/servo/io.hpp"

namespace hapticd::device::sim {
namespace {

std::uint64_t splitmix64(std::uint64_t x) noexcept {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

constexpr std::uint64_t kDropStream = 1;
constexpr std::uint64_t kLateStream = 2;

}  // namespace

bool FaultConfig::any() const {
    return disconnect_at_s >= 0.0 || stale_at_s >= 0.0 || jump_at_s >= 0.0 || !drop_at_s.empty() ||
           drop_probability > 0.0 || !late_at_s.empty() || late_probability > 0.0;
}

void FaultInjector::configure(const FaultConfig& faults, double period_s) {
    faults_ = faults;
    std::sort(faults_.drop_at_s.begin(), faults_.drop_at_s.end());
    std::sort(faults_.late_at_s.begin(), faults_.late_at_s.end());
    tolerance_s_ = 1e-6 * period_s;
    late_by_s_ = faults.late_by_s > 0.0 ? faults.late_by_s : 0.5 * period_s;
}

bool FaultInjector::reached(double at_s, double time_s) const noexcept {
    return at_s >= 0.0 && time_s + tolerance_s_ >= at_s;
}

bool FaultInjector::hit(double at_s, double previous_time_s, double time_s) const noexcept {
    return reached(at_s, time_s) && !(previous_time_s + tolerance_s_ >= at_s);
}

bool FaultInjector::any_hit(const std::vector<double>& sorted_s, double previous_time_s,
                            double time_s) const noexcept {
    // The first event after the previous sample; it hits if it is not after this one.
    const auto next =
        std::upper_bound(sorted_s.begin(), sorted_s.end(), previous_time_s + tolerance_s_);
    return next != sorted_s.end() && reached(*next, time_s);
}

double FaultInjector::uniform(std::uint64_t sequence, std::uint64_t stream) const noexcept {
    const std::uint64_t bits = splitmix64(faults_.seed ^ splitmix64(sequence * 4 + stream));
    return static_cast<double>(bits >> 11) * 0x1.0p-53;  // [0, 1)
}

bool FaultInjector::disconnected(double time_s) const noexcept {
    return reached(faults_.disconnect_at_s, time_s);
}

FaultVerdict FaultInjector::evaluate(double previous_time_s, double time_s,
                                     std::uint64_t sequence) const noexcept {
    FaultVerdict v;
    if (disconnected(time_s)) {
        v.disconnected = true;
        v.status |= servo::kStatusDisconnected;
        return v;  // nothing else arrives from a device that is gone
    }
    if (reached(faults_.stale_at_s, time_s) &&
        (faults_.stale_for_s < 0.0 ||
         time_s + tolerance_s_ < faults_.stale_at_s + faults_.stale_for_s)) {
        v.stale = true;
        v.status |= servo::kStatusStale;
    }
    if (reached(faults_.jump_at_s, time_s)) {
        v.jump_offset_counts = faults_.jump_counts;
        if (hit(faults_.jump_at_s, previous_time_s, time_s)) v.status |= servo::kStatusJump;
    }
    if (any_hit(faults_.drop_at_s, previous_time_s, time_s) ||
        (faults_.drop_probability > 0.0 &&
         uniform(sequence, kDropStream) < faults_.drop_probability)) {
        v.dropped = true;
        v.status |= servo::kStatusDropped;
    }
    if (any_hit(faults_.late_at_s, previous_time_s, time_s) ||
        (faults_.late_probability > 0.0 &&
         uniform(sequence, kLateStream) < faults_.late_probability)) {
        v.late = true;
        v.status |= servo::kStatusLate;
    }
    return v;
}

}  // namespace hapticd::device::sim
