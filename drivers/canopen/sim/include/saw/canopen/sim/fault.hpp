// Faults the simulated drive can be told to have, and how a command line or a YAML file names them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "saw/canopen/od.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/clock.hpp"

namespace saw::canopen::sim {

// The codes are what 0x2F00:01 ("Inject fault") takes; 0 there clears the lasting ones.
enum class FaultKind : std::uint8_t {
  over_current = 1,     // EMCY 0x2310, the drive goes to fault until a fault reset
  following_error = 2,  // EMCY 0x8611, the same as the window (0x6065) being exceeded
  heartbeat_loss = 3,   // the node stops producing heartbeats (everything else carries on)
  bus_off = 4,          // the node neither sends nor receives; EMCY 0x8140 once it recovers
  sdo_abort = 5,        // SDO transfers of one object are aborted with a given code
};
inline constexpr unsigned fault_kind_count = 5;

// "over-current", "following-error", "heartbeat-loss", "bus-off", "sdo-abort".
std::string_view to_string(FaultKind k) noexcept;
std::optional<FaultKind> fault_kind_from_string(std::string_view s) noexcept;
std::optional<FaultKind> fault_kind_from_code(unsigned code) noexcept;
// The kind's bit in 0x2F00:05 ("Active faults").
constexpr std::uint8_t fault_bit(FaultKind k) noexcept {
  return static_cast<std::uint8_t>(1U << (static_cast<unsigned>(k) - 1));
}
// Whether a fault lasts (until cleared or for a duration) rather than being one event that the
// drive latches in its fault state.
constexpr bool lasting(FaultKind k) noexcept {
  return k == FaultKind::heartbeat_loss || k == FaultKind::bus_off || k == FaultKind::sdo_abort;
}

// A bus-off that was given no duration ends after this long: the node cannot hear a clear.
inline constexpr TimeNs default_bus_off_duration = 1'000'000'000;

struct Fault {
  FaultKind kind = FaultKind::over_current;
  TimeNs duration = 0;                  // lasting kinds: how long; 0 until cleared (bus-off: 1 s)
  ObjectAddress object{};               // sdo_abort: the object whose transfers are refused
  SdoAbort abort = SdoAbort::hardware;  // sdo_abort: the code they are refused with
};

// A fault for one node at a time since the simulation started.
struct ScheduledFault {
  std::uint8_t node = 1;
  TimeNs at = 0;
  Fault fault;
};

// "<node>:<kind>:<at s>[:<duration s>]", the sdo-abort kind with its object and optionally its
// code: "2:sdo-abort=0x6064.0/0x06020000:1.5:3". Throws std::invalid_argument saying which part
// of `text` is wrong and what was expected.
ScheduledFault parse_scheduled_fault(std::string_view text);
// The fault part alone: "over-current", "sdo-abort=0x6064.0" (the kind and its arguments).
Fault parse_fault(std::string_view text);
// "node 2: sdo-abort 0x6064:00 (0x06060000) at 1.5 s for 3 s": for logs and the summary.
std::string describe(const ScheduledFault& f);

}  // namespace saw::canopen::sim
