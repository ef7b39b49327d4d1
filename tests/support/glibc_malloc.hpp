// glibc's own allocator entry points, which the malloc interposer (malloc_count.cpp) forwards
// to when it counts calls. glibc exports them under these reserved names; they are not in its
// headers.
#pragma once

#include <cstddef>

extern "C" {
// NOLINTBEGIN(bugprone-reserved-identifier): glibc's names, declared to be called
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* pointer, std::size_t size);
void __libc_free(void* pointer);
// NOLINTEND(bugprone-reserved-identifier)
}
