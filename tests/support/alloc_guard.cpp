// Counting replacements of the global allocation functions ([replacement.functions]). They
// forward to malloc/free (aligned_alloc for over-aligned types) and count per thread.
#include "alloc_guard.hpp"

#include <cstdlib>
#include <new>

#if HAPTICD_ALLOC_GUARD_HOOKS
#include <sanitizer/allocator_interface.h>
#endif

namespace {

// Plain integers: thread_local without dynamic initialisation, so no allocation here.
thread_local std::uint64_t t_allocations = 0;
thread_local std::uint64_t t_deallocations = 0;

#if HAPTICD_ALLOC_GUARD_HOOKS
void count_allocation(const volatile void*, std::size_t) { ++t_allocations; }
void count_deallocation(const volatile void* pointer) {
    if (pointer != nullptr) ++t_deallocations;
}
// Installed before main(), as the replacements are in place before main() in other builds.
[[maybe_unused]] const int g_hooks_installed =
    __sanitizer_install_malloc_and_free_hooks(count_allocation, count_deallocation);
#else
void* allocate(std::size_t size) noexcept {
    ++t_allocations;
    return std::malloc(size == 0 ? 1 : size);
}

void* allocate_aligned(std::size_t size, std::align_val_t alignment) noexcept {
    ++t_allocations;
    const auto align = static_cast<std::size_t>(alignment);
    std::size_t rounded = (size + align - 1) / align * align;
    if (rounded == 0) rounded = align;
    return std::aligned_alloc(align, rounded);
}

void release(void* pointer) noexcept {
    if (pointer == nullptr) return;
    ++t_deallocations;
    std::free(pointer);
}

void* allocate_or_throw(std::size_t size) {
    if (void* pointer = allocate(size)) return pointer;
    throw std::bad_alloc();
}

void* allocate_aligned_or_throw(std::size_t size, std::align_val_t alignment) {
    if (void* pointer = allocate_aligned(size, alignment)) return pointer;
    throw std::bad_alloc();
}

#endif  // HAPTICD_ALLOC_GUARD_HOOKS
}  // namespace

namespace hapticd::testing {
std::uint64_t thread_allocation_count() noexcept { return t_allocations; }
std::uint64_t thread_deallocation_count() noexcept { return t_deallocations; }
}  // namespace hapticd::testing

#if !HAPTICD_ALLOC_GUARD_HOOKS
void* operator new(std::size_t size) { return allocate_or_throw(size); }
void* operator new[](std::size_t size) { return allocate_or_throw(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocate(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocate(size); }
void* operator new(std::size_t size, std::align_val_t alignment) {
    return allocate_aligned_or_throw(size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
    return allocate_aligned_or_throw(size, alignment);
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
    return allocate_aligned(size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
    return allocate_aligned(size, alignment);
}

void operator delete(void* pointer) noexcept { release(pointer); }
void operator delete[](void* pointer) noexcept { release(pointer); }
void operator delete(void* pointer, std::size_t) noexcept { release(pointer); }
void operator delete[](void* pointer, std::size_t) noexcept { release(pointer); }
void operator delete(void* pointer, const std::nothrow_t&) noexcept { release(pointer); }
void operator delete[](void* pointer, const std::nothrow_t&) noexcept { release(pointer); }
void operator delete(void* pointer, std::align_val_t) noexcept { release(pointer); }
void operator delete[](void* pointer, std::align_val_t) noexcept { release(pointer); }
void operator delete(void* pointer, std::size_t, std::align_val_t) noexcept { release(pointer); }
void operator delete[](void* pointer, std::size_t, std::align_val_t) noexcept { release(pointer); }
void operator delete(void* pointer, std::align_val_t, const std::nothrow_t&) noexcept {
    release(pointer);
}
void operator delete[](void* pointer, std::align_val_t, const std::nothrow_t&) noexcept {
    release(pointer);
}
#endif  // !HAPTICD_ALLOC_GUARD_HOOKS
