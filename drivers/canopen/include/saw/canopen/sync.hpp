// SYNC (CiA 301 7.2.5): the producer the master runs each cycle, and the parse a node does.
#pragma once

#include <cstdint>
#include <optional>

#include "saw/can/frame.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// A SYNC frame on 0x080: empty, or with the counter (1..overflow) when 0x1019 enables it.
can::Frame sync_frame() noexcept;
can::Frame sync_frame(std::uint8_t counter) noexcept;

struct Sync {
  std::optional<std::uint8_t> counter;
};
// A SYNC, checked: identifier 0x080, 0 bytes, or 1 byte holding a counter in 1..240.
std::optional<Sync> parse_sync(const can::Frame& f) noexcept;

// Emits SYNC every period, with a counter when `overflow` (0x1019) is 2..240; 0 means none.
class SyncProducer {
 public:
  // Throws std::invalid_argument for a period not above 0 or an overflow of 1 or above 240.
  SyncProducer(TimeNs period, std::uint8_t overflow = 0);
  // The first SYNC is due at `now`; the counter restarts at 1 (CiA 301).
  void start(TimeNs now) noexcept;
  // The SYNC when one is due. Periods missed entirely (an overrun) are skipped, not burst: the
  // drives expect one SYNC per cycle, never two back to back.
  std::optional<can::Frame> poll(TimeNs now) noexcept;
  // The next SYNC now, out of the period's phase (a last one as the master stops): the counter
  // goes on, the schedule is untouched.
  can::Frame extra() noexcept;
  std::uint64_t skipped() const noexcept { return skipped_; }

 private:
  TimeNs period_;
  std::uint8_t overflow_;
  std::uint8_t counter_ = 1;
  TimeNs next_ = 0;
  std::uint64_t skipped_ = 0;
};

}  // namespace saw::canopen
