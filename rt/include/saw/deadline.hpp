// Deadline supervision: when a periodic task's lateness stops being jitter and becomes a fault.
#pragma once

#include <cstdint>

#include "saw/clock.hpp"

namespace saw {

// A periodic task's deadline is its period: a period in which no cycle started was missed. A
// loop that misses periods is not running the control it was tuned for (a law at a third of its
// rate, a drive holding a stale torque), so past a limit the task's components fault and take
// their safe state instead of driving on.
struct DeadlinePolicy {
  // Missed in a row: this many consecutive periods in which no cycle started (a stall). 0: not
  // checked.
  std::uint32_t in_a_row = 0;
  // Missed over a window: more than this share of the window's periods (a starved loop that
  // still runs now and then). 0: not checked.
  double share = 0;
  std::uint32_t window = 1000;  // periods: the share is judged once per window

  bool enabled() const noexcept { return in_a_row > 0 || share > 0; }
  // What a deployment gets unless it says otherwise: 50 periods in a row (50 ms at 1 kHz: a
  // stall past the staleness limits that fault a teleoperation's inputs, and past what a shared
  // VM's host does to its guests), or a tenth of the periods of 1000 (a starved loop, faulted
  // within about a second). A PC qualified for the work never comes near either: tighten it there.
  static constexpr DeadlinePolicy standard() noexcept { return {50, 0.1, 1000}; }
};

// One breach, with the figures a FAULT names.
struct DeadlineBreach {
  enum class Kind : std::uint8_t { in_a_row, share };
  Kind kind = Kind::in_a_row;
  std::uint64_t missed = 0;   // periods missed in a row, or in the window
  std::uint64_t periods = 0;  // the window's periods (share); `missed` (in a row)
  TimeNs latency = 0;         // how late the wake-up that saw it was
  TimeNs period = 0;
};

// Counts missed periods for one task, in its own thread (RT: no allocation, no lock).
class DeadlineMonitor {
 public:
  DeadlineMonitor() = default;
  DeadlineMonitor(DeadlinePolicy policy, TimeNs period) noexcept : policy_(policy), period_(period) {}

  // At a wake-up `latency` after its grid point, before the cycle runs: true (and `b` filled)
  // while the policy is breached. The periods in a row are the ones with no cycle start between
  // the last cycle's and this one: those the last cycle overran into, and those this wake-up is
  // late by (the pacer skips both at a cycle's end; the share counts them there).
  bool on_wakeup(TimeNs latency, DeadlineBreach& b) noexcept;
  // At the end of the cycle: the periods the pacer skipped to keep phase (0: on time).
  void on_finish(std::uint64_t skipped) noexcept;

  const DeadlinePolicy& policy() const noexcept { return policy_; }
  std::uint64_t in_a_row() const noexcept { return in_a_row_; }

 private:
  DeadlinePolicy policy_{};
  TimeNs period_ = 0;
  std::uint64_t in_a_row_ = 0;      // periods without a cycle start before this wake-up's
  std::uint64_t late_ = 0;          // periods this wake-up was late by
  std::uint64_t empty_before_ = 0;  // periods the last cycle overran into, beyond its own lateness
  std::uint64_t window_periods_ = 0, window_missed_ = 0;
  bool share_breached_ = false;  // the last full window's verdict, said at the next wake-up
  std::uint64_t share_missed_ = 0, share_periods_ = 0;
};

}  // namespace saw
