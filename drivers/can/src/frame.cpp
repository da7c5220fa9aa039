#include "saw/can/frame.hpp"

#include <algorithm>
#include <cstring>

namespace saw::can {

Frame classic(std::uint32_t id11, std::span<const std::uint8_t> bytes) noexcept {
  Frame f;
  f.id = id11 & CAN_SFF_MASK;
  f.len = static_cast<std::uint8_t>(std::min<std::size_t>(bytes.size(), CAN_MAX_DLEN));
  if (f.len > 0) std::memcpy(f.data, bytes.data(), f.len);
  return f;
}

bool valid_length(std::uint8_t len, bool fd) noexcept {
  if (len <= CAN_MAX_DLEN) return true;
  if (!fd) return false;
  switch (len) {
    case 12:
    case 16:
    case 20:
    case 24:
    case 32:
    case 48:
    case 64:
      return true;
    default:
      return false;
  }
}

bool well_formed(const Frame& f) noexcept {
  constexpr std::uint8_t known_flags = CANFD_FDF | CANFD_BRS | CANFD_ESI;
  if ((f.flags & ~known_flags) != 0) return false;
  if (!f.fd() && f.flags != 0) return false;  // BRS/ESI mean nothing on a classic frame
  if (f.fd() && f.remote()) return false;     // CAN FD has no remote frames
  if (!f.extended() && (f.id & CAN_EFF_MASK & ~CAN_SFF_MASK) != 0) return false;
  return valid_length(f.len, f.fd());
}

}  // namespace saw::can
