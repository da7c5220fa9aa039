// Forked helpers for benchmarks: servers that run until killed, and measurements that run in a
// process of their own (own network namespace, own DDS participant) and hand back samples.
#pragma once

#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "netns.hpp"
#include "saw/rt_thread.hpp"

namespace saw::bench {

struct Measured {
  std::vector<std::int64_t> samples;  // nanoseconds
  std::uint64_t failed = 0;
  bool completed = false;  // false: the child died or ran out of time
};

// Servers started with spawn(); all are killed (SIGKILL) and reaped by kill_all() or at the end.
class Children {
 public:
  ~Children() { kill_all(); }
  // Runs `body` (which does not return) in a child in namespace `ns`, pinned to `cpu` (-1: any).
  template <class F>
  pid_t spawn(const std::string& ns, int cpu, F body) {
    const pid_t pid = fork();
    if (pid == 0) {
      (void)prctl(PR_SET_PDEATHSIG, SIGKILL);
      enter_netns(ns);
      if (cpu >= 0) (void)saw::rt::set_affinity(cpu);
      body();
      std::_Exit(0);
    }
    pids_.push_back(pid);
    return pid;
  }
  void kill_all() {
    for (const pid_t p : pids_) kill(p, SIGKILL);
    for (const pid_t p : pids_) waitpid(p, nullptr, 0);
    pids_.clear();
  }

 private:
  std::vector<pid_t> pids_;
};

// Runs `body(failed)` -> std::vector<std::int64_t> in a child (namespace `ns`, CPU `cpu`) and
// returns what it measured; a child that has not finished within `limit` is killed.
template <class F>
Measured measure_in_child(const std::string& ns, int cpu, std::size_t capacity, std::chrono::seconds limit,
                          F body) {
  struct Header {
    std::atomic<std::uint64_t> count{0}, failed{0};
    std::atomic<bool> done{false};
  };
  const std::size_t bytes = sizeof(Header) + capacity * sizeof(std::int64_t);
  void* area = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (area == MAP_FAILED) return {};
  auto* h = new (area) Header;
  auto* data = reinterpret_cast<std::int64_t*>(static_cast<char*>(area) + sizeof(Header));
  const pid_t pid = fork();
  if (pid == 0) {
    (void)prctl(PR_SET_PDEATHSIG, SIGKILL);
    enter_netns(ns);
    if (cpu >= 0) (void)saw::rt::set_affinity(cpu);
    std::uint64_t failed = 0;
    const std::vector<std::int64_t> v = body(failed);
    const std::size_t n = std::min(v.size(), capacity);
    std::memcpy(data, v.data(), n * sizeof(std::int64_t));
    h->count.store(n, std::memory_order_relaxed);
    h->failed.store(failed, std::memory_order_relaxed);
    h->done.store(true, std::memory_order_release);
    std::_Exit(0);
  }
  Measured m;
  const auto deadline = std::chrono::steady_clock::now() + limit;
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (h->done.load(std::memory_order_acquire)) {
    m.completed = true;
    m.failed = h->failed.load(std::memory_order_relaxed);
    m.samples.assign(data, data + h->count.load(std::memory_order_relaxed));
  }
  munmap(area, bytes);
  return m;
}

}  // namespace saw::bench
