// Process and thread set-up for real-time work: scheduling, affinity, memory locking.
#pragma once

#include <string>

namespace saw::rt {

// Each returns an empty string on success, else what failed and why (errno text).
std::string set_fifo(int priority);  // SCHED_FIFO for the calling thread
std::string set_affinity(int cpu);   // pin the calling thread
std::string lock_memory();           // mlockall(MCL_CURRENT | MCL_FUTURE)
void prefault_stack(std::size_t bytes);

// Holds /dev/cpu_dma_latency at 0 while alive (the kernel restores it when the fd closes).
class DmaLatencyHold {
 public:
  DmaLatencyHold();
  ~DmaLatencyHold();
  DmaLatencyHold(const DmaLatencyHold&) = delete;
  DmaLatencyHold& operator=(const DmaLatencyHold&) = delete;
  const std::string& error() const noexcept { return error_; }

 private:
  int fd_ = -1;
  std::string error_;
};

}  // namespace saw::rt
