#include "saw/deadline.hpp"

namespace saw {

bool DeadlineMonitor::on_wakeup(TimeNs latency, DeadlineBreach& b) noexcept {
  if (period_ <= 0) return false;
  late_ = latency > 0 ? static_cast<std::uint64_t>(latency / period_) : 0;
  in_a_row_ = empty_before_ + late_;
  b.latency = latency;
  b.period = period_;
  if (policy_.in_a_row > 0 && in_a_row_ >= policy_.in_a_row) {
    b.kind = DeadlineBreach::Kind::in_a_row;
    b.missed = b.periods = in_a_row_;
    return true;
  }
  if (share_breached_) {
    share_breached_ = false;
    b.kind = DeadlineBreach::Kind::share;
    b.missed = share_missed_;
    b.periods = share_periods_;
    return true;
  }
  return false;
}

void DeadlineMonitor::on_finish(std::uint64_t skipped) noexcept {
  // The pacer's skipped grid points include the ones this cycle woke late by (counted at its
  // wake-up, in the run that ended with this cycle's start); the rest passed while it ran.
  empty_before_ = skipped > late_ ? skipped - late_ : 0;
  if (policy_.share <= 0) return;
  window_periods_ += 1 + skipped;
  window_missed_ += skipped;
  if (window_periods_ < policy_.window) return;
  if (static_cast<double>(window_missed_) > policy_.share * static_cast<double>(window_periods_)) {
    share_breached_ = true;
    share_missed_ = window_missed_;
    share_periods_ = window_periods_;
  }
  window_periods_ = window_missed_ = 0;
}

}  // namespace saw
