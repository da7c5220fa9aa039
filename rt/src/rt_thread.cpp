#include "saw/rt_thread.hpp"

#include <alloca.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>

namespace saw::rt {

std::string set_fifo(int priority) {
  sched_param p{};
  p.sched_priority = priority;
  if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e != 0)
    return "SCHED_FIFO priority " + std::to_string(priority) + ": " + std::strerror(e);
  return {};
}

std::string set_affinity(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e != 0)
    return "affinity to CPU " + std::to_string(cpu) + ": " + std::strerror(e);
  return {};
}

std::string lock_memory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return std::string("mlockall: ") + std::strerror(errno);
  return {};
}

void prefault_stack(std::size_t bytes) {
  // Touch the pages the loop may use so the first overrun is not a page fault.
  // Atomic stores, so the compiler cannot drop them as dead.
  auto* p = static_cast<std::uint8_t*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096)
    std::atomic_ref<std::uint8_t>(p[i]).store(0, std::memory_order_relaxed);
}

DmaLatencyHold::DmaLatencyHold() {
  fd_ = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) {
    error_ = std::string("/dev/cpu_dma_latency: ") + std::strerror(errno);
    return;
  }
  const std::int32_t zero = 0;
  if (::write(fd_, &zero, sizeof zero) != sizeof zero) {
    error_ = std::string("/dev/cpu_dma_latency write: ") + std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
  }
}

DmaLatencyHold::~DmaLatencyHold() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace saw::rt
