// RPDO deadline monitoring (CiA 301): the node watches the master's RPDOs through their event timers.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "saw/canopen/eds.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// CiA 301 (v4.2, 7.5.2.35) gives an RPDO's event timer (0x1400 + n - 1, sub-index 05h, ms) a
// meaning on the receiving side: a deadline. Once an RPDO came in operational, a node that gets
// none for that long signals EMCY 0x8250 (RPDO timeout) and reacts (a CiA 402 drive as 0x6007
// says). A master whose loop is starved while its bus task still sends SYNC and heartbeats is
// thus seen by the drives, which no heartbeat consumer would notice.
//
// The start-up writes it to every enabled RPDO after the PDOs (node_writes), and a
// re-configuration after a reboot writes it again. Each write is optional: a node without the
// sub-index (abort "sub-index does not exist") simply cannot watch.
struct RpdoDeadline {
  // nullopt: the node's event timers are left as they are (nothing written); 0: monitoring off
  // (0 written, so a device default does not stay on).
  std::optional<TimeNs> time;
  // RPDO numbers whose EDS lists no writable sub-index 05h: not written (the node cannot watch).
  std::vector<std::uint16_t> unwritable;
};

// The object's unit: whole milliseconds, rounded up (a deadline is never shortened); 65535 at most.
std::uint16_t deadline_ms(TimeNs t) noexcept;

// Set-up: the deadline of a component run every `period`: nullopt → max(5 ms, 3 periods); an
// explicit one must be 0 (off) or, in whole ms, at least two periods (one late cycle is not a
// starved master) and at most 65535 ms. Throws std::invalid_argument saying which.
TimeNs resolve_rpdo_deadline(std::optional<TimeNs> deadline, TimeNs period);

// The enabled RPDOs of `pdos` whose event timer `eds` does not list, or lists read-only.
std::vector<std::uint16_t> rpdos_without_event_timer(const Eds& eds, std::span<const PdoMapping> pdos);

// After the start-up: the enabled RPDOs that do not watch a deadline that is on, because their
// write was not made (an EDS without the object) or not acknowledged (the node refused it as
// absent); `written` is what the node acknowledged (StartupSequence::written()). Empty when the
// deadline is off or not written at all. For the component's warning.
std::vector<std::uint16_t> unwatched_rpdos(std::span<const PdoMapping> pdos, const RpdoDeadline& deadline,
                                           std::span<const SdoWrite> written);

}  // namespace saw::canopen
