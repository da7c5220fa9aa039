// CANopen identifiers (function code plus node-ID) and the check every received frame passes.
#pragma once

#include <cstdint>

#include "saw/can/frame.hpp"

namespace saw::canopen {

// The predefined connection set of CiA 301 (7.3.5): COB-ID = function code + node-ID.
namespace cob {
inline constexpr std::uint32_t nmt = 0x000;
inline constexpr std::uint32_t sync = 0x080;
inline constexpr std::uint32_t emcy = 0x080;  // + node 1..127
inline constexpr std::uint32_t tpdo1 = 0x180;
inline constexpr std::uint32_t rpdo1 = 0x200;
inline constexpr std::uint32_t sdo_tx = 0x580;  // server to client (responses)
inline constexpr std::uint32_t sdo_rx = 0x600;  // client to server (requests)
inline constexpr std::uint32_t heartbeat = 0x700;
}  // namespace cob

inline constexpr std::uint8_t max_node_id = 127;
constexpr bool valid_node_id(unsigned node) noexcept { return node >= 1 && node <= max_node_id; }

// A frame CANopen may use: well formed, classic, 11-bit identifier, data (not remote, not error).
// CANopen (CiA 301) speaks classic CAN only; an FD or extended frame on a CANopen identifier is
// someone else's traffic or a fault, never a message to act on.
bool canopen_data_frame(const can::Frame& f) noexcept;

}  // namespace saw::canopen
