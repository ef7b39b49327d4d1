// The clock of FrameLink::receive()'s deadlines.
#include "hapticd/device/link/frame_link.hpp"

#include <ctime>

namespace hapticd::device::link {

std::int64_t monotonic_now_ns() noexcept {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace hapticd::device::link
