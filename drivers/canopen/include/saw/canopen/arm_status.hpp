// Why a CANopen component went to FAULT, and what a run of it comes to (its summary column).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <tuple>

#include "saw/crtk.hpp"
#include "saw/device.hpp"
#include "saw/fault.hpp"

namespace saw::canopen {

// The CANopen reason behind a FaultInfo (whose code is the generic one).
enum class FaultReason : std::uint8_t {
  none,
  drive_fault,      // a statusword showed fault, or an enable's fault resets did not clear it
                    // (detail: 0x603F when mapped, else the last EMCY's code)
  emcy,             // an EMCY, and the drive's statusword then in fault (detail: the code)
  heartbeat_lost,   // no heartbeat within heartbeat_timeout (age: how long it was silent)
  node_rebooted,    // a boot-up after start-up: the drive's configuration is gone (restart needed)
  bus_off,          // the bus is off or down (detail: can::BusState)
  feedback_stale,   // no TPDO within feedback_timeout (age: the newest one's)
  command_stale,    // no servo command within command_timeout (on_command_timeout: fault)
  joint_limit,      // a measured position left [min, max]
  following_error,  // CSP: |target − position| above following_error
  enable_timeout,   // a drive did not reach operation enabled within the transition timeout
                    // (detail: its statusword, whose state it was stuck in)
  mode_mismatch,    // 0x6061 did not show the mode written to 0x6060 (detail: asked << 8 | shown)
  nmt_left,         // the drive's heartbeat said it left NMT operational (detail: the NMT state)
};
constexpr std::size_t enum_count(FaultReason) { return 13; }
constexpr std::string_view enum_type_name(FaultReason) { return "saw::canopen::FaultReason"; }
// Lower case, a literal (the RT log keeps the pointer): "heartbeat lost".
const char* to_string(FaultReason r) noexcept;

// Commands refused before they became a PDO, by why: the device base's count.
using saw::RefusedCommands;

// A CANopen component's state and counters: a summary column (printed when a run ends).
struct CanopenStatus {
  static constexpr std::string_view type_name = "saw::canopen::CanopenStatus";
  // 2: refused is the device base's; 3: fault_node, warnings; 4: shared_bus; 5: the base's counts
  // (refused commands, watchdog trips, command_timeout) are the base's DeviceStatus alone
  static constexpr std::uint32_t layout_version = 5;
  OperatingStateValue state = OperatingStateValue::disabled;
  FaultReason reason = FaultReason::none;  // the last fault's (kept after recovery, as `fault`)
  std::uint8_t bus_state = 0;              // can::BusState
  std::uint8_t joints = 0;
  std::uint8_t shared_bus = 0;  // 1: a client of a bus task (its SYNC and heartbeat are the task's)
  std::uint32_t faults = 0;     // times it went to FAULT
  FaultInfo fault;              // the last fault (kept after recovery)
  std::uint8_t fault_node = 0;  // its drive's node-ID (0: the bus, or none)
  // EMCYs that were warnings (the drive stayed out of fault), and the newest one
  std::uint64_t warnings = 0;
  std::uint16_t last_warning = 0;
  std::uint8_t last_warning_register = 0, last_warning_node = 0;
  std::uint64_t frames_received = 0, frames_sent = 0, send_refused = 0, foreign_frames = 0;
  std::uint64_t syncs = 0;
  std::uint64_t emcy = 0, heartbeat_losses = 0, bad_pdos = 0;
  std::uint64_t sdo_done = 0, sdo_failed = 0, sdo_refused = 0;
  static constexpr auto fields = std::tuple{&CanopenStatus::state,
                                            &CanopenStatus::reason,
                                            &CanopenStatus::bus_state,
                                            &CanopenStatus::joints,
                                            &CanopenStatus::shared_bus,
                                            &CanopenStatus::faults,
                                            &CanopenStatus::fault,
                                            &CanopenStatus::fault_node,
                                            &CanopenStatus::warnings,
                                            &CanopenStatus::last_warning,
                                            &CanopenStatus::last_warning_register,
                                            &CanopenStatus::last_warning_node,
                                            &CanopenStatus::frames_received,
                                            &CanopenStatus::frames_sent,
                                            &CanopenStatus::send_refused,
                                            &CanopenStatus::foreign_frames,
                                            &CanopenStatus::syncs,
                                            &CanopenStatus::emcy,
                                            &CanopenStatus::heartbeat_losses,
                                            &CanopenStatus::bad_pdos,
                                            &CanopenStatus::sdo_done,
                                            &CanopenStatus::sdo_failed,
                                            &CanopenStatus::sdo_refused};
};

}  // namespace saw::canopen
