// The simulated drive's object dictionary: an EDS (or the built-in sim_drive.eds), completed with what the
// simulation uses.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/eds.hpp"

namespace saw::canopen::sim {

// The text of drivers/canopen/sim/sim_drive.eds, compiled into the library (installed beside
// it as share/sawrt/sim_drive.eds, for masters that read it).
std::string_view builtin_eds() noexcept;
inline constexpr const char* builtin_eds_name = "sim_drive.eds (built in)";

// The EDS or DCF at `path`, or the built-in one when `path` is empty. Throws
// saw::deploy::ConfigError naming file:line:column and key.
Eds load_drive_eds(const std::string& path);

// The simulator's fault-injection record (manufacturer area; see README "Fault injection").
namespace injection_object {
inline constexpr std::uint16_t index = 0x2F00;
inline constexpr ObjectAddress inject{index, 1};    // UNSIGNED8: write a FaultKind code; 0 clears
inline constexpr ObjectAddress duration{index, 2};  // UNSIGNED32 ms: how long a lasting fault lasts
inline constexpr ObjectAddress object{index, 3};    // UNSIGNED32: index << 16 | sub << 8 (sdo-abort)
inline constexpr ObjectAddress code{index, 4};      // UNSIGNED32: the abort code (sdo-abort)
inline constexpr ObjectAddress active{index, 5};    // UNSIGNED8 ro: fault_bit() of each active fault
}  // namespace injection_object

// make_dictionary(eds, node), plus every object the simulation reads or writes that the file
// does not define (0x6040 .. 0x6077, 0x1001, 0x1017, the injection record, ...), added with
// its CiA 301/402 type, access and PDO mappability, so that any CiA 402 EDS makes a working
// drive. Throws ConfigError where the file defines one of them with another type.
LocalDictionary make_drive_dictionary(const Eds& eds, std::uint8_t node);

}  // namespace saw::canopen::sim
