// CommandWatchdog: how a device notices that its commands stopped coming, and says so.
#pragma once

#include <cstdint>

#include "saw/clock.hpp"
#include "saw/state_table.hpp"

namespace saw {

// A device that takes force or position commands must not keep applying the last one when its
// commander dies (a crashed teleoperation process left a master pushing the operator's hand): it
// drops to zero force or holds when no fresh command came within its timeout. This keeps the
// deadline and, as state columns, whether it holds now and how often it tripped. Used from the
// device's own thread only; allocates nothing after set-up.
class CommandWatchdog {
 public:
  // Adds the columns "command_timeout" (bool: holding, for lack of commands) and
  // "watchdog_trips" (count) to `table` (set-up, before the table is finalized).
  explicit CommandWatchdog(StateTable& table)
      : holding_column_(table.add_column("command_timeout", &holding_)),
        trips_column_(table.add_column("watchdog_trips", &trips_)) {}
  CommandWatchdog(const CommandWatchdog&) = delete;  // the table reads these fields in place
  CommandWatchdog& operator=(const CommandWatchdog&) = delete;

  void set_timeout(TimeNs timeout) noexcept { timeout_ = timeout; }
  TimeNs timeout() const noexcept { return timeout_; }

  // A command came at `now` (its handler's time). A refused command counts too: the device
  // zeroes its output for it, so the commander is alive.
  void commanded(TimeNs now) noexcept {
    last_ = now;
    armed_ = true;
    holding_ = false;
  }
  // True once, in the first cycle more than the timeout after the last command: then the device
  // drops its output. Commands handled before a cycle carry its time, so a commander that sends
  // every period is never older than one period here.
  bool expired(TimeNs now) noexcept {
    if (!armed_ || now - last_ <= timeout_) return false;
    armed_ = false;
    holding_ = true;
    ++trips_;
    return true;
  }
  // The output was dropped for another reason (disable, a fault): nothing to watch until the
  // next command.
  void disarm() noexcept { armed_ = false; }

  bool holding() const noexcept { return holding_; }
  std::uint64_t trips() const noexcept { return trips_; }
  TimeNs last_command() const noexcept { return last_; }
  StateColumn<bool> holding_column() const noexcept { return holding_column_; }
  StateColumn<std::uint64_t> trips_column() const noexcept { return trips_column_; }

 private:
  TimeNs timeout_ = 0;
  TimeNs last_ = 0;
  bool armed_ = false;    // a command came and has not timed out yet
  bool holding_ = false;  // the last command timed out and no new one came
  std::uint64_t trips_ = 0;
  StateColumn<bool> holding_column_;
  StateColumn<std::uint64_t> trips_column_;
};

}  // namespace saw
