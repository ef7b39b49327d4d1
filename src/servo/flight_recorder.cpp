#include "hapticd/servo/flight_recorder.hpp"

#include <stdexcept>

namespace hapticd::servo {

FlightRecorder::FlightRecorder(std::size_t capacity) {
    if (capacity == 0) throw std::invalid_argument("flight recorder: capacity must be >= 1");
    ring_.resize(capacity);
}

std::vector<TelemetryRecord> FlightRecorder::frozen_records() const {
    if (!frozen()) return {};
    const std::size_t held =
        recorded_ < ring_.size() ? static_cast<std::size_t>(recorded_) : ring_.size();
    std::vector<TelemetryRecord> records;
    records.reserve(held);
    for (std::uint64_t i = recorded_ - held; i < recorded_; ++i) {
        records.push_back(ring_[static_cast<std::size_t>(i % ring_.size())]);
    }
    return records;
}

}  // namespace hapticd::servo
