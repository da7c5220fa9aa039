#include "saw/canopen/sync.hpp"

#include <stdexcept>
#include <string>

#include "saw/canopen/cob.hpp"

namespace saw::canopen {

can::Frame sync_frame() noexcept { return can::classic(cob::sync, {}); }

can::Frame sync_frame(std::uint8_t counter) noexcept { return can::classic(cob::sync, {&counter, 1}); }

std::optional<Sync> parse_sync(const can::Frame& f) noexcept {
  if (!canopen_data_frame(f) || f.can_id() != cob::sync) return std::nullopt;
  if (f.len == 0) return Sync{};
  if (f.len == 1 && f.data[0] >= 1 && f.data[0] <= 240) return Sync{f.data[0]};
  return std::nullopt;
}

SyncProducer::SyncProducer(TimeNs period, std::uint8_t overflow) : period_(period), overflow_(overflow) {
  if (period <= 0) throw std::invalid_argument("SYNC producer: the period must be above 0");
  if (overflow == 1 || overflow > 240)
    throw std::invalid_argument("SYNC producer: counter overflow " + std::to_string(overflow) +
                                " is not 0 (no counter) or 2..240");
}

void SyncProducer::start(TimeNs now) noexcept {
  next_ = now;
  counter_ = 1;
}

std::optional<can::Frame> SyncProducer::poll(TimeNs now) noexcept {
  if (now < next_) return std::nullopt;
  const TimeNs behind = (now - next_) / period_;  // whole periods missed
  skipped_ += static_cast<std::uint64_t>(behind);
  next_ += (behind + 1) * period_;
  return extra();
}

can::Frame SyncProducer::extra() noexcept {
  if (overflow_ == 0) return sync_frame();
  const std::uint8_t c = counter_;
  counter_ = counter_ >= overflow_ ? 1 : static_cast<std::uint8_t>(counter_ + 1);
  return sync_frame(c);
}

}  // namespace saw::canopen
