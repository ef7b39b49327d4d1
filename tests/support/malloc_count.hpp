// Counting the C allocator's calls on each thread. alloc_guard.hpp counts operator new, which
// is what our code would use; a C library (hidapi, libusb, libudev, libumockdev-preload) calls
// malloc() directly. Linking hapticd::malloc_count into a test executable interposes malloc,
// calloc, realloc and free (forwarding to glibc's own, glibc_malloc.hpp) for the whole
// process, so that a test can show what a tick allocates, libraries included.
//
// ASan and TSan own malloc and refuse an interposer: under them (HAPTICD_ALLOC_GUARD_HOOKS)
// nothing is interposed, thread_heap_calls() does not exist, and thread_malloc_count() is
// the allocation guard's count, which their hooks make count malloc() too. Link
// hapticd::alloc_guard beside hapticd::malloc_count.
#pragma once

#include <cstdint>

#include "alloc_guard.hpp"

namespace hapticd::testing {

/// Heap calls by kind.
struct HeapCalls {
    std::uint64_t malloc = 0;
    std::uint64_t calloc = 0;
    std::uint64_t realloc = 0;
    std::uint64_t free = 0;  ///< of a non-null pointer

    /// The calls made since `earlier`, a count taken before on the same thread.
    constexpr HeapCalls operator-(const HeapCalls& earlier) const noexcept {
        return {malloc - earlier.malloc, calloc - earlier.calloc, realloc - earlier.realloc,
                free - earlier.free};
    }
};

#if !HAPTICD_ALLOC_GUARD_HOOKS
/// The heap calls made on the calling thread since it started. Reading it does not allocate.
HeapCalls thread_heap_calls() noexcept;
#endif

/// malloc + calloc + realloc calls on the calling thread since it started.
std::uint64_t thread_malloc_count() noexcept;

}  // namespace hapticd::testing
