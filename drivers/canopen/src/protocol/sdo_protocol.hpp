// The SDO wire format shared by the client and the server (CiA 301 7.2.4.3): command bytes,
// the multiplexer, and the one frame length SDO uses.
#pragma once

#include <cstdint>

#include "saw/can/frame.hpp"
#include "saw/canopen/od.hpp"

namespace saw::canopen::sdo {

inline constexpr std::uint8_t frame_length = 8;  // every SDO frame carries 8 bytes

// Command specifiers, bits 7..5 of byte 0: client requests (ccs) and server responses (scs).
namespace ccs {
inline constexpr std::uint8_t download_segment = 0;
inline constexpr std::uint8_t initiate_download = 1;
inline constexpr std::uint8_t initiate_upload = 2;
inline constexpr std::uint8_t upload_segment = 3;
}  // namespace ccs
namespace scs {
inline constexpr std::uint8_t upload_segment = 0;
inline constexpr std::uint8_t download_segment = 1;
inline constexpr std::uint8_t initiate_upload = 2;
inline constexpr std::uint8_t initiate_download = 3;
}  // namespace scs
inline constexpr std::uint8_t abort_cs = 4;  // the same for both directions

inline constexpr std::uint8_t specifier(const can::Frame& f) noexcept { return f.data[0] >> 5; }

// Initiate frames: e (expedited, bit 1), s (size indicated, bit 0), n (bits 3..2: bytes of
// the 4-byte data field that are not data, valid when e and s).
inline constexpr std::uint8_t bit_e = 0x02;
inline constexpr std::uint8_t bit_s = 0x01;
// Segment frames: t (toggle, bit 4), n (bits 3..1: bytes of the 7 that are not data), c (last).
inline constexpr std::uint8_t bit_t = 0x10;
inline constexpr std::uint8_t bit_c = 0x01;
inline constexpr std::uint8_t segment_data = 7;

inline ObjectAddress multiplexer(const can::Frame& f) noexcept {
  return {static_cast<std::uint16_t>(f.data[1] | (f.data[2] << 8)), f.data[3]};
}

inline std::uint32_t u32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

inline void put_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// An 8-byte frame on `cob_id` with command byte `command` (and the multiplexer, second form).
inline can::Frame frame(std::uint32_t cob_id, std::uint8_t command) noexcept {
  can::Frame f;
  f.id = cob_id & CAN_SFF_MASK;
  f.len = frame_length;
  f.data[0] = command;
  return f;
}

inline can::Frame frame(std::uint32_t cob_id, std::uint8_t command, ObjectAddress a) noexcept {
  can::Frame f = frame(cob_id, command);
  f.data[1] = static_cast<std::uint8_t>(a.index);
  f.data[2] = static_cast<std::uint8_t>(a.index >> 8);
  f.data[3] = a.subindex;
  return f;
}

}  // namespace saw::canopen::sdo
