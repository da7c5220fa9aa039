// ReportStream: the bytes the Falcon sends, in; the newest complete report, out.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "saw/drivers/falcon/packet.hpp"

namespace saw::drivers::falcon {

// Bytes arrive in transfers that need not match packets: a report may be split over two, and
// when the host falls behind (a late cycle, a slow I/O thread) several wait in the FTDI. Only
// the newest tells where the arms are, so take_newest() returns it and drops every older one,
// as libnifalcon's I/O loop does: a backlog never builds and a report is never one exchange
// late for good. A frame is '<', 15 bytes, '>' ('<' never occurs inside one: every payload
// byte is 'A' + a value); bytes that frame nothing are dropped, resynchronising on the next '<'.
// Fixed storage: no allocation, for the cycle.
class ReportStream {
 public:
  static constexpr std::size_t capacity = 8 * packet_size;

  // The data bytes of one transfer (the FTDI's status bytes already off). When the buffer would
  // overflow, the oldest bytes go: they can only hold older reports.
  void push(std::span<const std::uint8_t> bytes) noexcept;
  // The newest complete frame into `out`, consuming it and all before it; a partial frame at the
  // end stays for the next transfer. False: no complete frame (`out` untouched).
  bool take_newest(Packet& out) noexcept;
  void clear() noexcept { count_ = 0; }

  std::size_t buffered() const noexcept { return count_; }
  std::uint64_t skipped() const noexcept { return skipped_; }  // older reports dropped for a newer one

 private:
  std::array<std::uint8_t, capacity> buffer_{};
  std::size_t count_ = 0;
  std::uint64_t skipped_ = 0;
};

}  // namespace saw::drivers::falcon
