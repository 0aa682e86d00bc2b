#pragma once
/// @file allocation_counter.hpp  Counts heap allocations of a test executable, for the tests that
/// check a query's fast path allocates nothing: replaces the global operator new / delete.
/// Include it from exactly one translation unit per executable (every test executable is one
/// file), then compare allocationCount() before and after the queries.

#include <atomic>
#include <cstdlib>
#include <new>

namespace crux::test {
inline std::atomic<long> gAllocations{0};
/// Heap allocations made so far by this executable.
inline long allocationCount() { return gAllocations.load(); }
}  // namespace crux::test

void* operator new(std::size_t n) {
  ++crux::test::gAllocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  ++crux::test::gAllocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
