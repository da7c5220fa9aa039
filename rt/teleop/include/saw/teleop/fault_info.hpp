// FaultSide: which of the teleoperation task's two devices a FaultInfo (saw/fault.hpp) is about.
#pragma once

#include <cstdint>
#include <string_view>

#include "saw/fault.hpp"

namespace saw::teleop {

// The generic fault, under the names teleop code has always used.
using saw::FaultCode;
using saw::FaultInfo;
using saw::to_string;

// Which input (or peer behind it) the check was about; a FaultInfo's source is its name.
enum class FaultSide : std::uint8_t { none, master, slave };

constexpr std::string_view to_string(FaultSide s) {
  switch (s) {
    case FaultSide::none:
      return "";
    case FaultSide::master:
      return "master";
    case FaultSide::slave:
      return "slave";
  }
  return "?";
}

// The side a fault's source names (none for another source); its to_string is a literal, which
// the RT log can hold where it cannot hold the fault's own characters.
constexpr FaultSide side_of(const FaultInfo& f) noexcept {
  for (auto s : {FaultSide::master, FaultSide::slave})
    if (f.source_name() == to_string(s)) return s;
  return FaultSide::none;
}

// A fault about one side (RT-safe: no allocation).
FaultInfo fault_on(FaultSide side, FaultCode code, Status last_read = Status::ok, TimeNs age_ns = 0) noexcept;

}  // namespace saw::teleop
