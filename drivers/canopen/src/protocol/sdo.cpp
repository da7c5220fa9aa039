#include "saw/canopen/sdo.hpp"

#include "sdo_protocol.hpp"

namespace saw::canopen {

std::string_view sdo_abort_name(std::uint32_t code) noexcept {
  switch (static_cast<SdoAbort>(code)) {
    case SdoAbort::none:
      return "no abort";
    case SdoAbort::toggle_bit:
      return "toggle bit not alternated";
    case SdoAbort::timeout:
      return "SDO protocol timed out";
    case SdoAbort::command_specifier:
      return "client/server command specifier not valid or unknown";
    case SdoAbort::block_size:
      return "invalid block size (block mode only)";
    case SdoAbort::sequence_number:
      return "invalid sequence number (block mode only)";
    case SdoAbort::crc:
      return "CRC error (block mode only)";
    case SdoAbort::out_of_memory:
      return "out of memory";
    case SdoAbort::unsupported_access:
      return "unsupported access to an object";
    case SdoAbort::write_only:
      return "attempt to read a write only object";
    case SdoAbort::read_only:
      return "attempt to write a read only object";
    case SdoAbort::no_object:
      return "object does not exist in the object dictionary";
    case SdoAbort::not_mappable:
      return "object cannot be mapped to the PDO";
    case SdoAbort::pdo_too_long:
      return "the number and length of the objects to be mapped would exceed PDO length";
    case SdoAbort::parameter_incompatible:
      return "general parameter incompatibility reason";
    case SdoAbort::internal_incompatible:
      return "general internal incompatibility in the device";
    case SdoAbort::hardware:
      return "access failed due to a hardware error";
    case SdoAbort::length_mismatch:
      return "data type does not match, length of service parameter does not match";
    case SdoAbort::length_too_high:
      return "data type does not match, length of service parameter too high";
    case SdoAbort::length_too_low:
      return "data type does not match, length of service parameter too low";
    case SdoAbort::no_subindex:
      return "sub-index does not exist";
    case SdoAbort::invalid_value:
      return "invalid value for parameter (download only)";
    case SdoAbort::value_too_high:
      return "value of parameter written too high (download only)";
    case SdoAbort::value_too_low:
      return "value of parameter written too low (download only)";
    case SdoAbort::max_below_min:
      return "maximum value is less than minimum value";
    case SdoAbort::no_resource:
      return "resource not available: SDO connection";
    case SdoAbort::general:
      return "general error";
    case SdoAbort::cannot_store:
      return "data cannot be transferred or stored to the application";
    case SdoAbort::local_control:
      return "data cannot be transferred or stored to the application because of local control";
    case SdoAbort::device_state:
      return "data cannot be transferred or stored to the application because of the present device state";
    case SdoAbort::no_dictionary:
      return "object dictionary dynamic generation fails or no object dictionary is present";
    case SdoAbort::no_data:
      return "no data available";
  }
  return "not a standard SDO abort code";
}

SdoAbort abort_for(Codec c) noexcept {
  switch (c) {
    case Codec::ok:
      return SdoAbort::none;
    case Codec::wrong_length:
      return SdoAbort::length_mismatch;
    case Codec::too_high:
      return SdoAbort::value_too_high;
    case Codec::too_low:
      return SdoAbort::value_too_low;
    case Codec::invalid:
      return SdoAbort::invalid_value;
  }
  return SdoAbort::general;
}

can::Frame sdo_abort_frame(std::uint32_t cob_id, ObjectAddress address, SdoAbort code) noexcept {
  can::Frame f = sdo::frame(cob_id, sdo::abort_cs << 5, address);
  sdo::put_u32(f.data + 4, static_cast<std::uint32_t>(code));
  return f;
}

}  // namespace saw::canopen
