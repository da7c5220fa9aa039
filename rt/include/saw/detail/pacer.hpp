// Pacer: a periodic task's absolute wake-up grid, with overrun accounting that keeps phase (internal).
#pragma once

#include <cstdint>

#include "saw/clock.hpp"

namespace saw::detail {

// Wake-ups are start + k·period, never "now + period", so the rate cannot drift. A cycle
// that ends past its next wake-up skips whole periods and stays on the grid.
class Pacer {
 public:
  Pacer(TimeNs start, TimeNs period) noexcept : next_(start), period_(period) {}

  TimeNs next_wakeup() const noexcept { return next_; }
  TimeNs period() const noexcept { return period_; }

  // Called when a cycle that woke for next_wakeup() ends at `end`: moves to the next grid
  // point after `end` and returns the number of wake-ups skipped (0 when on time).
  std::uint64_t finish_cycle(TimeNs end) noexcept {
    next_ += period_;
    if (end < next_) return 0;
    const auto missed = static_cast<std::uint64_t>((end - next_) / period_) + 1;
    next_ += static_cast<TimeNs>(missed) * period_;
    ++overruns_;
    missed_ += missed;
    return missed;
  }

  std::uint64_t overruns() const noexcept { return overruns_; }      // cycles that ran late
  std::uint64_t missed_periods() const noexcept { return missed_; }  // wake-ups skipped

 private:
  TimeNs next_;
  TimeNs period_;
  std::uint64_t overruns_ = 0;
  std::uint64_t missed_ = 0;
};

}  // namespace saw::detail
