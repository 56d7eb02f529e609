// Replaces the global operator new of the test program that includes it (include it in
// exactly one source file of a program) with one that counts, so that a test can check
// that a hot path allocates nothing: read allocation_count() before and after.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace shtool::test {
inline std::atomic<long> g_allocations{0};
inline long allocation_count() { return g_allocations.load(std::memory_order_relaxed); }
}  // namespace shtool::test

// noinline: GCC 12 otherwise inlines free() into callers that it sees calling operator
// new and warns (-Wmismatched-new-delete) about a pairing that is correct here.
[[gnu::noinline]] void* operator new(std::size_t n) {
  shtool::test::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
