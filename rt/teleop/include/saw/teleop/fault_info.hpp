// FaultSide: which of the teleoperation task's two devices a FaultInfo (saw/fault.hpp) is about.
#pragma once

#include <array>
#include <cstddef>
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

// Why a FAULT happened, in more words than a FaultInfo holds (a setting's two values, the two
// components): written in RT code without allocating, truncated at `max` characters.
struct FaultText {
  static constexpr std::size_t max = 255;
  std::array<char, max + 1> text{};  // NUL-terminated
  std::size_t size = 0;

  void clear() noexcept { *this = {}; }
  FaultText& append(std::string_view s) noexcept;
  // The shortest decimal that reads back as v (std::to_chars: no locale, no allocation).
  FaultText& append(double v) noexcept;
  std::string_view view() const noexcept { return {text.data(), size}; }
};

}  // namespace saw::teleop
