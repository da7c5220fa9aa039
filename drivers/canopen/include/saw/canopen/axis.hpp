// One CiA 402 drive as the bus master runs it: its configuration, and what each cycle reads of it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "saw/canopen/cia402.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/rpdo_deadline.hpp"
#include "saw/canopen/units.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// CiA 402's abort connection option code (0x6007): what a drive does when it loses its master
// (its heartbeat consumer fires, bus-off, ...) while it is driving.
enum class AbortConnection : std::int16_t { none = 0, fault = 1, disable_voltage = 2, quick_stop = 3 };

// What a drive must say it is (0x1000, 0x1018:01, 0x1018:02), as its EDS/DCF says: checked at
// start-up, before anything is written to it.
struct DriveIdentity {
  std::string file;  // the EDS/DCF that says so (named in the error)
  std::uint32_t device_type = 0, vendor_id = 0, product_code = 0;
};

struct AxisConfig {
  std::string name;  // the joint's name: what faults and logs call it
  std::uint8_t node = 1;
  cia402::Mode mode = cia402::csp;  // written to 0x6060 at start-up; its target is the one sent
  DriveUnits units;
  // Every PDO the start-up configures (disabled ones are written as not valid). The RPDOs must
  // map the controlword and the mode's target, the TPDOs the statusword and position actual.
  std::vector<PdoMapping> pdos;
  // The drive sends its heartbeat this often (0x1017, written at start-up) ...
  TimeNs heartbeat_period = 100'000'000;
  // ... and is lost when none came for this long (the master's consumer time; above the period).
  TimeNs heartbeat_timeout = 250'000'000;
  // The drive watches the master's heartbeat (0x1016:01, written at start-up: the master's
  // node-ID and this time; 0: not watched) and, once it is missing, does what 0x6007 says.
  std::uint8_t master_node = 127;
  TimeNs master_timeout = 300'000'000;
  AbortConnection abort_connection = AbortConnection::quick_stop;
  // The drive watches the master's RPDOs too (their event timers): a starved master whose SYNC
  // and heartbeat go on is seen, and 0x6007 acts. Resolved by the component (default: on).
  RpdoDeadline rpdo_deadline;
  std::optional<DriveIdentity> identity;  // nullopt: not checked (no EDS given)
  // The deployment's own SDO writes (0x60C2 interpolation period, vendor objects), written at
  // start-up after 0x6007 and before 0x6060, in this order.
  std::vector<SdoWrite> writes;
};

// The object that carries the mode's target: 0x607A (csp), 0x60FF (csv), 0x6071 (cst).
ObjectAddress mode_target(cia402::Mode mode) noexcept;

// Set-up: throws std::invalid_argument naming the axis and what is wrong (node-ID, units,
// heartbeat times, a PDO that check() refuses, the objects the mode needs not mapped).
void check(const AxisConfig& a);

// What the last TPDOs said about a drive, in SI (units.hpp). Velocity is the drive's when a TPDO
// maps 0x606C, else the difference of positions; torque is the joint's effort (through the gear)
// when 0x6077 is mapped, else 0.
struct AxisFeedback {
  bool valid = false;        // every TPDO arrived at least once (since the start, or a re-configuration)
  TimeNs watch_from = 0;     // not valid: stale counts from here (a re-configuration's end), or the start
  bool fresh = false;        // a TPDO arrived since the last cycle
  TimeNs last_received = 0;  // when the last TPDO arrived (the cycle's time)
  std::uint16_t statusword = 0;
  cia402::State state = cia402::State::unknown;
  std::int8_t mode_display = 0;  // 0x6061 when mapped, else 0
  bool has_mode_display = false;
  std::uint16_t error_code = 0;  // 0x603F when mapped, else 0
  bool has_error_code = false;
  std::int32_t position_counts = 0;
  double position = 0, velocity = 0, torque = 0;
  bool has_velocity = false, has_torque = false;
};

// What the master heard about a drive besides its PDOs. Counters only grow: a reader compares
// them with the values it saw last.
struct AxisHealth {
  bool heartbeat_seen = false;
  bool heartbeat_lost = false;  // silent for longer than heartbeat_timeout, not back yet
  TimeNs silent_for = 0;        // at the last loss
  std::uint32_t heartbeat_losses = 0;
  std::uint32_t boot_ups = 0;  // boot-ups after start-up: the drive reset, its set-up is gone
  NmtState nmt_state = NmtState::initialising;
  std::uint64_t emcy_count = 0;     // EMCY messages with an error (code not 0)
  std::uint16_t last_emcy = 0;      // the newest one's code
  std::uint8_t error_register = 0;  // from the newest EMCY (0 after an error reset)
  std::uint64_t bad_pdos = 0;       // frames on a TPDO identifier of the wrong length or kind
};

// What one heartbeat-consumer event says of a node's health (a drive's or an I/O node's).
void note_heartbeat(AxisHealth& h, const HeartbeatEvent& e) noexcept;

}  // namespace saw::canopen
