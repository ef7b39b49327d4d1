// What an AllocationGuard (alloc_guard.hpp) sees libusb allocate on the ticking thread. For
// the tests that link hapticd::alloc_guard.
#pragma once

#include <cstdint>

#include "alloc_guard.hpp"

namespace hapticd::testing {

/// The allocations counted for `transfers` submitted transfers: libusb's Linux backend
/// calloc()s each one's URB (usb_heap_test.cpp), which the guard counts only where it counts
/// malloc() too (under ASan and TSan). Our own code allocates nothing either way.
constexpr std::uint64_t libusb_urb_allocations(std::uint64_t transfers) {
    return kAllocationGuardCountsMalloc ? transfers : 0;
}

}  // namespace hapticd::testing
