// malloc, calloc and realloc counted per thread (malloc_count.hpp), forwarding to glibc's
// __libc_* functions (whose free() is the one every caller uses).
#include "malloc_count.hpp"

#include <cstddef>

#include "alloc_guard.hpp"

#if HAPTICD_ALLOC_GUARD_HOOKS
// ASan and TSan own malloc; their hooks (alloc_guard.cpp) count it with operator new.
namespace hapticd::testing {
std::uint64_t thread_malloc_count() noexcept { return thread_allocation_count(); }
}  // namespace hapticd::testing
#else

#include "glibc_malloc.hpp"

namespace {
// Constant-initialised static TLS: reading it never allocates.
__thread std::uint64_t t_mallocs = 0;
}  // namespace

extern "C" {
void* malloc(std::size_t size) {
    ++t_mallocs;
    return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
    ++t_mallocs;
    return __libc_calloc(count, size);
}
void* realloc(void* pointer, std::size_t size) {
    ++t_mallocs;
    return __libc_realloc(pointer, size);
}
}

namespace hapticd::testing {
std::uint64_t thread_malloc_count() noexcept { return t_mallocs; }
}  // namespace hapticd::testing
#endif  // HAPTICD_ALLOC_GUARD_HOOKS
