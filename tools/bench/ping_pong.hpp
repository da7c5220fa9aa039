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

// n round trips of two words in a shared mapping; the parent (the caller) times each; the child
// runs on child_cpu (-1: any). Each side waits for its word asleep on a futex (Sleep) or spinning.
template <bool Sleep>
std::vector<std::int64_t> ping_pong(int n, int child_cpu) {
  struct Words {
    alignas(64) std::atomic<std::uint32_t> ping{0};
    alignas(64) std::atomic<std::uint32_t> pong{0};
  };
  const auto await = [](std::atomic<std::uint32_t>& word, std::uint32_t i) {
    while (word.load(std::memory_order_acquire) != i)
      if constexpr (Sleep) saw::bridge::futex_wait(word, i - 1, 0);
  };
  const auto post = [](std::atomic<std::uint32_t>& word, std::uint32_t i) {
    word.store(i, std::memory_order_release);
    if constexpr (Sleep) saw::bridge::futex_wake_all(word);
  };
  auto* w =
      new (mmap(nullptr, sizeof(Words), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0)) Words;
  const pid_t pid = fork();
  if (pid == 0) {
    if (child_cpu >= 0) (void)saw::rt::set_affinity(child_cpu);
    for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(n); ++i) {
      await(w->ping, i);
      post(w->pong, i);
    }
    std::_Exit(0);
  }
  std::vector<std::int64_t> out(static_cast<std::size_t>(n));
  for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(n); ++i) {
    const auto t0 = saw::monotonic_now();
    post(w->ping, i);
    await(w->pong, i);
    out[i - 1] = saw::monotonic_now() - t0;
  }
  waitpid(pid, nullptr, 0);
  munmap(w, sizeof(Words));
  return out;
}

// The floor for a sleeping waiter.
inline std::vector<std::int64_t> futex_ping_pong(int n, int child_cpu) {
  return ping_pong<true>(n, child_cpu);
}
// The floor for a spinning one: two cache-line transfers.
inline std::vector<std::int64_t> spin_ping_pong(int n, int child_cpu) {
  return ping_pong<false>(n, child_cpu);
}

}  // namespace saw::bench
