// malloc, calloc, realloc and free counted per thread (malloc_count.hpp), forwarding to
// glibc's __libc_* functions.
#include "malloc_count.hpp"

#include <cstddef>

#if HAPTICD_ALLOC_GUARD_HOOKS
// ASan and TSan own malloc; their hooks (alloc_guard.cpp) count it with operator new.
namespace hapticd::testing {
std::uint64_t thread_malloc_count() noexcept { return thread_allocation_count(); }
}  // namespace hapticd::testing
#else

#include "glibc_malloc.hpp"

namespace {
// Constant-initialised, trivially destructible static TLS: reading or counting never
// allocates (no initialisation guard, no TLS wrapper call).
constinit thread_local hapticd::testing::HeapCalls t_calls{};
}  // namespace

// The executable's definitions come first in symbol lookup, so these see every call made by
// our code, libstdc++ and the C libraries (hidapi, libusb, libudev, the umockdev preload).
extern "C" {
void* malloc(std::size_t size) {
    ++t_calls.malloc;
    return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
    ++t_calls.calloc;
    return __libc_calloc(count, size);
}
void* realloc(void* pointer, std::size_t size) {
    ++t_calls.realloc;
    return __libc_realloc(pointer, size);
}
void free(void* pointer) {
    if (pointer != nullptr) ++t_calls.free;
    __libc_free(pointer);
}
}

namespace hapticd::testing {
HeapCalls thread_heap_calls() noexcept { return t_calls; }
std::uint64_t thread_malloc_count() noexcept {
    return t_calls.malloc + t_calls.calloc + t_calls.realloc;
}
}  // namespace hapticd::testing
#endif  // HAPTICD_ALLOC_GUARD_HOOKS
