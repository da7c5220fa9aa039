// RtGuard: what the threads inside an RT path did that an RT path must not do (see rt_guard.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace saw::testing {

struct GuardCounts {
  // Violations, each made while saw::in_rt_context() was true.
  std::uint64_t allocations = 0;         // malloc family
  std::uint64_t locks = 0;               // mutex and rwlock acquisitions
  std::uint64_t waits = 0;               // condition variable, semaphore and futex waits
  std::uint64_t stdio = 0;               // printf family, puts, fwrite, write to fd 1 or 2
  std::uint64_t voluntary_switches = 0;  // the thread blocked between wake-up and next sleep
  std::uint64_t minor_faults = 0;        // page faults between wake-up and next sleep
  // Not violations: evidence of what ran.
  std::uint64_t futex_wakes = 0;  // FUTEX_WAKE calls (non-blocking) from an RT cycle
  std::uint64_t cycles = 0;       // RT cycles the guard sampled (begin to end)
  std::size_t first_allocation_size = 0;
  std::string first_violation;  // "<kind> in task '<name>'", empty if none

  std::uint64_t violations() const noexcept {
    return allocations + locks + waits + stdio + voluntary_switches + minor_faults;
  }
};

// Counts what RT threads do from its construction on. Construct it before the components:
// every RT cycle is then checked from the thread's first one (set-up and start are not RT).
class GuardWindow {
 public:
  GuardWindow() noexcept;
  GuardCounts counts() const;

 private:
  GuardCounts start_;
};

// Whether the guard binary locked its memory (mlockall) at start-up, as saw-rt does: only then
// is a page fault in a cycle a defect of the code under test rather than of the set-up.
bool memory_locked() noexcept;
// Why it did not (the mlockall error and the limit), or empty when it did.
std::string memory_lock_error();

std::string describe(const GuardCounts& c);

}  // namespace saw::testing
