#include "hapticd/daemon/run_notes.hpp"

namespace hapticd::daemon {

std::optional<std::uint32_t> RunNotes::add(std::string text,
                                           const std::function<void(std::uint32_t)>& publish) {
    const std::lock_guard lock(mutex_);
    if (texts_.size() >= kMaxRunNotes) return std::nullopt;
    texts_.push_back(std::move(text));
    const auto number = static_cast<std::uint32_t>(texts_.size());
    publish(number);
    return number;
}

std::string RunNotes::text(std::uint32_t number) const {
    const std::lock_guard lock(mutex_);
    if (number == 0 || number > texts_.size()) return {};
    return texts_[number - 1];
}

}  // namespace hapticd::daemon
