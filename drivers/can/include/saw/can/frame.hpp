// One CAN or CAN FD frame as Linux lays it out (struct canfd_frame), plus the time it was seen.
#pragma once

#include <linux/can.h>

#include <cstddef>
#include <cstdint>
#include <span>

#include "saw/clock.hpp"

namespace saw::can {

// Byte-for-byte struct canfd_frame, so SocketCAN reads and writes it without copying; a classic
// frame (struct can_frame) is its first 16 bytes. `flags` carries CANFD_FDF for an FD frame.
struct Frame {
  std::uint32_t id = 0;    // identifier | CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG
  std::uint8_t len = 0;    // payload bytes: 0..8, or an FD length (12, 16, 20, 24, 32, 48, 64)
  std::uint8_t flags = 0;  // CANFD_FDF | CANFD_BRS | CANFD_ESI
  std::uint8_t reserved0 = 0;
  std::uint8_t reserved1 = 0;
  alignas(8) std::uint8_t data[CANFD_MAX_DLEN] = {};

  bool fd() const noexcept { return (flags & CANFD_FDF) != 0; }
  bool extended() const noexcept { return (id & CAN_EFF_FLAG) != 0; }
  bool remote() const noexcept { return (id & CAN_RTR_FLAG) != 0; }
  bool error() const noexcept { return (id & CAN_ERR_FLAG) != 0; }
  // The identifier without flags: 11 bits, or 29 for an extended frame.
  std::uint32_t can_id() const noexcept { return id & (extended() ? CAN_EFF_MASK : CAN_SFF_MASK); }
  std::span<const std::uint8_t> payload() const noexcept { return {data, len}; }
};
static_assert(sizeof(Frame) == sizeof(canfd_frame));
static_assert(offsetof(Frame, data) == offsetof(canfd_frame, data));
static_assert(offsetof(Frame, len) == offsetof(canfd_frame, len));

// A frame as received: when the bus (the kernel's timestamp where there is one) saw it.
struct Received {
  Frame frame;
  TimeNs time = 0;  // CLOCK_MONOTONIC
};

// A classic data frame with an 11-bit identifier (what CANopen sends). `bytes` beyond 8 are cut.
Frame classic(std::uint32_t id11, std::span<const std::uint8_t> bytes) noexcept;

// Whether `len` is a length a frame of this kind may have (classic 0..8; FD the DLC table).
bool valid_length(std::uint8_t len, bool fd) noexcept;

// Whether a frame read from outside the process may be used: identifier within its mask, a valid
// length for its kind, no reserved bit set. Every frame from a bus is checked with it.
bool well_formed(const Frame& f) noexcept;

}  // namespace saw::can
