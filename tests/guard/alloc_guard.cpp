// Replaces malloc and friends (and pthread_mutex_lock) for the guard test binary: each call
// made from a thread marked as RT (saw::in_rt_context()) is counted as a violation.
#include "alloc_guard.hpp"

#include <dlfcn.h>
#include <pthread.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>

#include "saw/rt_context.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
}

namespace {
std::atomic<std::uint64_t> allocations{0};
std::atomic<std::uint64_t> locks{0};
std::atomic<std::size_t> first_size{0};

void note_allocation(std::size_t size) noexcept {
  if (!saw::in_rt_context()) return;
  if (allocations.fetch_add(1, std::memory_order_relaxed) == 0)
    first_size.store(size, std::memory_order_relaxed);
}

using MutexLockFn = int (*)(pthread_mutex_t*);
MutexLockFn real_mutex_lock() noexcept {
  static const auto fn = reinterpret_cast<MutexLockFn>(dlsym(RTLD_NEXT, "pthread_mutex_lock"));
  return fn;
}
// Resolve before any test thread runs: dlsym itself may allocate.
[[maybe_unused]] const MutexLockFn resolved_early = real_mutex_lock();
}  // namespace

namespace saw::testing {
GuardCounts guard_counts() noexcept {
  return {allocations.load(std::memory_order_relaxed), locks.load(std::memory_order_relaxed),
          first_size.load(std::memory_order_relaxed)};
}
void guard_reset() noexcept {
  allocations.store(0, std::memory_order_relaxed);
  locks.store(0, std::memory_order_relaxed);
  first_size.store(0, std::memory_order_relaxed);
}
}  // namespace saw::testing

extern "C" {
void* malloc(std::size_t n) {
  note_allocation(n);
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t m) {
  note_allocation(n * m);
  return __libc_calloc(n, m);
}
void* realloc(void* p, std::size_t n) {
  note_allocation(n);
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
void* aligned_alloc(std::size_t a, std::size_t n) {
  note_allocation(n);
  return __libc_memalign(a, n);
}
void* memalign(std::size_t a, std::size_t n) {
  note_allocation(n);
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, std::size_t a, std::size_t n) {
  note_allocation(n);
  void* p = __libc_memalign(a, n);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
int pthread_mutex_lock(pthread_mutex_t* m) {
  if (saw::in_rt_context()) locks.fetch_add(1, std::memory_order_relaxed);
  return real_mutex_lock()(m);
}
}
