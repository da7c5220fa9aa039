// Bare ping-pongs between two processes, per round trip: over a futex (the floor for a sleeping
// waiter) and over two spinning atomics (the floor for a spinning one: two cache-line transfers).
#pragma once

#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <new>
#include <vector>

#include "saw/bridge/futex.hpp"
#include "saw/clock.hpp"
#include "saw/rt_thread.hpp"

namespace saw::bench {

// n round trips; the parent (the caller) times each; the child runs on child_cpu (-1: any).
inline std::vector<std::int64_t> futex_ping_pong(int n, int child_cpu) {
  struct Words {
    alignas(64) std::atomic<std::uint32_t> ping{0};
    alignas(64) std::atomic<std::uint32_t> pong{0};
  };
  auto* w =
      new (mmap(nullptr, sizeof(Words), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0)) Words;
  const pid_t pid = fork();
  if (pid == 0) {
    if (child_cpu >= 0) (void)saw::rt::set_affinity(child_cpu);
    for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(n); ++i) {
      while (w->ping.load(std::memory_order_acquire) != i) saw::bridge::futex_wait(w->ping, i - 1, 0);
      w->pong.store(i, std::memory_order_release);
      saw::bridge::futex_wake_all(w->pong);
    }
    std::_Exit(0);
  }
  std::vector<std::int64_t> out(static_cast<std::size_t>(n));
  for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(n); ++i) {
    const auto t0 = saw::monotonic_now();
    w->ping.store(i, std::memory_order_release);
    saw::bridge::futex_wake_all(w->ping);
    while (w->pong.load(std::memory_order_acquire) != i) saw::bridge::futex_wait(w->pong, i - 1, 0);
    out[i - 1] = saw::monotonic_now() - t0;
  }
  waitpid(pid, nullptr, 0);
  munmap(w, sizeof(Words));
  return out;
}

// n round trips of two atomics in a shared mapping, both sides spinning; as futex_ping_pong.
inline std::vector<std::int64_t> spin_ping_pong(int n, int child_cpu) {
  struct Words {
    alignas(64) std::atomic<std::uint32_t> ping{0};
    alignas(64) std::atomic<std::uint32_t> pong{0};
  };
  auto* w =
      new (mmap(nullptr, sizeof(Words), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0)) Words;
  const pid_t pid = fork();
  if (pid == 0) {
    if (child_cpu >= 0) (void)saw::rt::set_affinity(child_cpu);
    for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(n); ++i) {
      while (w->ping.load(std::memory_order_acquire) != i) {
      }
      w->pong.store(i, std::memory_order_release);
    }
    std::_Exit(0);
  }
  std::vector<std::int64_t> out(static_cast<std::size_t>(n));
  for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(n); ++i) {
    const auto t0 = saw::monotonic_now();
    w->ping.store(i, std::memory_order_release);
    while (w->pong.load(std::memory_order_acquire) != i) {
    }
    out[i - 1] = saw::monotonic_now() - t0;
  }
  waitpid(pid, nullptr, 0);
  munmap(w, sizeof(Words));
  return out;
}

}  // namespace saw::bench
