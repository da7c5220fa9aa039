// SDO abort codes (CiA 301 7.2.4.3.17) and the identifiers both ends of an SDO channel share.
#pragma once

#include <cstdint>
#include <string_view>

#include "saw/can/frame.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/od.hpp"

namespace saw::canopen {

// The standard abort codes. A value outside this list is still carried (a vendor's own code);
// sdo_abort_name() then says it is not a standard one.
enum class SdoAbort : std::uint32_t {
  none = 0,
  toggle_bit = 0x05030000,
  timeout = 0x05040000,
  command_specifier = 0x05040001,
  block_size = 0x05040002,
  sequence_number = 0x05040003,
  crc = 0x05040004,
  out_of_memory = 0x05040005,
  unsupported_access = 0x06010000,
  write_only = 0x06010001,
  read_only = 0x06010002,
  no_object = 0x06020000,
  not_mappable = 0x06040041,
  pdo_too_long = 0x06040042,
  parameter_incompatible = 0x06040043,
  internal_incompatible = 0x06040047,
  hardware = 0x06060000,
  length_mismatch = 0x06070010,
  length_too_high = 0x06070012,
  length_too_low = 0x06070013,
  no_subindex = 0x06090011,
  invalid_value = 0x06090030,
  value_too_high = 0x06090031,
  value_too_low = 0x06090032,
  max_below_min = 0x06090036,
  no_resource = 0x060A0023,
  general = 0x08000000,
  cannot_store = 0x08000020,
  local_control = 0x08000021,
  device_state = 0x08000022,
  no_dictionary = 0x08000023,
  no_data = 0x08000024,
};

// The meaning of an abort code as CiA 301 states it, lower case:
// sdo_abort_name(0x06020000) is "object does not exist in the object dictionary".
std::string_view sdo_abort_name(std::uint32_t code) noexcept;
inline std::string_view to_string(SdoAbort a) noexcept {
  return sdo_abort_name(static_cast<std::uint32_t>(a));
}

// The abort a server gives for a value the codec refused.
SdoAbort abort_for(Codec c) noexcept;

// The two identifiers of an SDO channel, from the client's side.
struct SdoChannel {
  std::uint32_t request = 0;   // client to server
  std::uint32_t response = 0;  // server to client
  // A node's default server SDO (0x600 + node, 0x580 + node).
  static constexpr SdoChannel of_node(std::uint8_t node) noexcept {
    return {cob::sdo_rx + node, cob::sdo_tx + node};
  }
};

// An abort transfer frame (command specifier 4) on `cob_id` for the transfer at `address`.
can::Frame sdo_abort_frame(std::uint32_t cob_id, ObjectAddress address, SdoAbort code) noexcept;

}  // namespace saw::canopen
