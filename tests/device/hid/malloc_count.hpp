// Counts the C allocator's calls on each thread. alloc_guard.hpp counts operator new, which
// is what our code would use; a C library (hidapi, libudev, libumockdev-preload) calls
// malloc() directly. Linking malloc_count.cpp into a test executable interposes malloc,
// calloc and realloc (forwarding to glibc's own) for the whole process, so that a test can
// show that a tick allocates nowhere, libraries included.
#pragma once

#include <cstdint>

namespace hapticd::testing {

/// malloc + calloc + realloc calls on the calling thread since it started.
std::uint64_t thread_malloc_count() noexcept;

}  // namespace hapticd::testing
