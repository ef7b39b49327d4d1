// An allocation guard for tests, in the style of Drake's LimitMalloc: link a test binary
// with hapticd::alloc_guard (which replaces the global operator new/delete with counting
// versions) and wrap the code that must not allocate:
//
//     hapticd::testing::AllocationGuard guard;
//     for (int i = 0; i < 10000; ++i) loop.tick();
//     EXPECT_EQ(guard.allocations(), 0u);
//
// Counts are per thread: the guard sees what the thread that created it allocates, not what
// other threads do. Every form of operator new is counted (plain, array, aligned, nothrow);
// direct calls to malloc() are not, except under ASan and TSan, where the sanitizer's hooks
// count every allocation.
#pragma once

#include <cstdint>

// ThreadSanitizer and AddressSanitizer define operator new themselves, so under them the
// guard counts through the sanitizer's allocation hooks instead: every allocation of the
// program, operator new and malloc alike (a stricter count than the replacements').
#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
#define HAPTICD_ALLOC_GUARD_HOOKS 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer) || __has_feature(address_sanitizer)
#define HAPTICD_ALLOC_GUARD_HOOKS 1
#endif
#endif
#ifndef HAPTICD_ALLOC_GUARD_HOOKS
#define HAPTICD_ALLOC_GUARD_HOOKS 0
#endif

namespace hapticd::testing {

/// True when the guard counts every allocation, a C library's malloc() included (the
/// sanitizers' hooks); false when it counts operator new only.
inline constexpr bool kAllocationGuardCountsMalloc = HAPTICD_ALLOC_GUARD_HOOKS != 0;

/// Allocations (operator new calls) made on the calling thread since it started.
std::uint64_t thread_allocation_count() noexcept;
/// Deallocations (operator delete calls with a non-null pointer) on the calling thread.
std::uint64_t thread_deallocation_count() noexcept;

class AllocationGuard {
  public:
    AllocationGuard() noexcept
        : allocations_at_start_(thread_allocation_count()),
          deallocations_at_start_(thread_deallocation_count()) {}

    AllocationGuard(const AllocationGuard&) = delete;
    AllocationGuard& operator=(const AllocationGuard&) = delete;

    /// Allocations on this thread since the guard was created.
    std::uint64_t allocations() const noexcept {
        return thread_allocation_count() - allocations_at_start_;
    }
    std::uint64_t deallocations() const noexcept {
        return thread_deallocation_count() - deallocations_at_start_;
    }

  private:
    std::uint64_t allocations_at_start_;
    std::uint64_t deallocations_at_start_;
};

}  // namespace hapticd::testing
