// PDO entries as a deployment file writes them ("target_position", "0x2001:01:i32"), and the default maps.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "saw/canopen/cia402.hpp"
#include "saw/canopen/pdo.hpp"

namespace saw::canopen {

// The type of a CiA 402 (or CiA 301) object the master knows by itself, so that a deployment
// maps it without spelling its type; nullopt for any other object.
std::optional<DataType> known_object_type(ObjectAddress a) noexcept;

// One entry of a PDO as text:
//   a name       controlword, statusword, mode_of_operation, mode_display, error_code,
//                target_position, target_velocity, target_torque, position_actual,
//                velocity_actual, torque_actual
//   an address   "0x6041:00" or "6041:0" (hex index, sub-index) of an object known_object_type knows
//   with a type  "0x2001:01:i32" (types: bool, i8, i16, i32, i64, u8, u16, u32, u64, f32, f64)
// Throws std::invalid_argument saying what is wrong with the text.
PdoEntry parse_pdo_entry(std::string_view text);

// A mapping of `kind` number `number` for `node` with the predefined identifier (PDOs 1..4; a
// higher number needs `cob_id`), transmitted on every SYNC; throws as check() does.
PdoMapping make_pdo(PdoKind kind, std::uint16_t number, std::uint8_t node, std::span<const PdoEntry> entries,
                    std::optional<std::uint32_t> cob_id = std::nullopt);

// PDO `number` of `node` configured as not valid (its predefined identifier with bit 31 clear in
// the mapping, nothing mapped): so that a node's factory PDOs do not load the bus.
PdoMapping unused_pdo(PdoKind kind, std::uint16_t number, std::uint8_t node) noexcept;

// What the master maps when the deployment says nothing: RPDO1 controlword + the mode's target
// (target position, velocity or torque); TPDO1 statusword + position actual + torque actual,
// TPDO2 velocity actual + modes of operation display + error code; PDOs 2..4 (RPDO) and 3..4 (TPDO)
// configured as not valid, so that a drive's factory TPDOs do not load the bus.
std::vector<PdoMapping> default_pdo_mappings(cia402::Mode mode, std::uint8_t node);

}  // namespace saw::canopen
