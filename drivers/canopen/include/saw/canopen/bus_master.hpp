// The CANopen master of one bus, run by one periodic RT task: frames in, CiA 402 drives, RPDOs and SYNC out.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/axis.hpp"
#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/canopen/sdo_queue.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

struct BusMasterConfig {
  TimeNs period = 1'000'000;         // the task's period: one SYNC per cycle
  std::uint8_t sync_overflow = 0;    // SYNC counter overflow (0x1019): 0 none, else 2..240
  TimeNs sdo_timeout = 500'000'000;  // each response of a runtime SDO transfer
  std::size_t sdo_queue = 16;        // runtime SDO requests (and replies) in flight
  std::size_t max_frames = 256;      // frames read per cycle at most; the rest wait a cycle
  bool sync = true;                  // false: another (a shared bus task) sends SYNC
  // The master's own heartbeat (CiA 301), which the drives' consumers (0x1016) watch: its
  // node-ID (no drive may have it) and period; 0: none.
  std::uint8_t node = 127;
  TimeNs heartbeat_period = 100'000'000;
  cia402::ControllerConfig controller;
};

// A drive's configuration run again from the cycle (a drive that rebooted): the start-up's SDO
// writes through its SDO channel, then NMT start and an operational heartbeat.
struct Reconfiguration {
  enum class State : std::uint8_t { idle, busy, done, failed } state = State::idle;
  ObjectAddress object{};           // failed: the write refused (0x0000: no operational heartbeat)
  SdoAbort abort = SdoAbort::none;  // ... and why
};

// Figures since construction; each only grows.
struct MasterCounters {
  std::uint64_t cycles = 0;
  std::uint64_t frames_received = 0;
  std::uint64_t frames_sent = 0;
  std::uint64_t send_refused = 0;  // frames the bus did not take (full, down)
  std::uint64_t syncs = 0;
  std::uint64_t heartbeats = 0;                // the master's own
  std::uint64_t foreign_frames = 0;            // frames for no drive of this master (another master's, ...)
  std::uint64_t receive_limited = 0;           // cycles that left frames for the next (max_frames)
  std::uint64_t emcy = 0;                      // EMCY messages, error resets included
  std::uint64_t sdo_done = 0, sdo_failed = 0;  // runtime SDO transfers
  std::uint64_t heartbeat_events_dropped = 0;
};

// The cycle, called by the owning task in this order:
//   receive(now)   every frame that arrived (non-blocking, at most max_frames): TPDOs (the drives'
//                  answer to the previous SYNC) to their drives, heartbeats to the consumer
//                  (lost, back, boot-up), EMCY decoded, SDO responses to their client
//   ...            the owner reads feedback() and health(), decides, and sets targets
//   transmit(now)  each drive's CiA 402 controller on the statusword just read; RPDOs packed
//                  and sent; a runtime SDO transfer stepped; SYNC last, so that every drive has
//                  its RPDO before the SYNC that applies it; the master's heartbeat when due.
// receive() and transmit() neither allocate, lock, block, print nor throw. Construction and
// start-up (StartupSequence, on the set-up thread) happen before the first cycle.
class BusMaster {
 public:
  // Throws std::invalid_argument naming the axis and the problem (see check(AxisConfig)), and
  // for two axes that share a node-ID or a PDO identifier.
  BusMaster(can::Bus& bus, BusMasterConfig config, std::vector<AxisConfig> axes);
  ~BusMaster();
  BusMaster(const BusMaster&) = delete;
  BusMaster& operator=(const BusMaster&) = delete;

  can::Bus& bus() noexcept;
  std::size_t size() const noexcept;
  const AxisConfig& axis(std::size_t i) const noexcept;

  void receive(TimeNs now) noexcept;
  const AxisFeedback& feedback(std::size_t i) const noexcept;
  const AxisHealth& health(std::size_t i) const noexcept;

  // Where the controller walks the drive, and a fault reset (a rising edge of bit 7 once the
  // drive is in fault).
  void set_state_target(std::size_t i, cia402::Target t, TimeNs now) noexcept;
  void request_fault_reset(std::size_t i, TimeNs now) noexcept;
  // The mode's target in SI (rad or m, per second, or the joint's effort in N·m or N through the
  // gear): converted to drive units and packed.
  // A value the conversion or the PDO entry refuses is not packed (the previous one stays) and
  // the reason is returned.
  Codec set_setpoint(std::size_t i, double si) noexcept;
  // The last setpoint packed, in SI.
  double setpoint(std::size_t i) const noexcept;

  void transmit(TimeNs now) noexcept;
  // The last frames of a master that stops: every drive's RPDOs with `controlword` (disable
  // voltage, or quick stop) and the setpoints as set, one SYNC so that the drives take them at
  // once, then NMT enter pre-operational for every node. Sent before it returns.
  void shut_down(std::uint16_t controlword, TimeNs now) noexcept;
  // Starts re-running drive i's configuration (a drive that rebooted), stepped by transmit();
  // its feedback counts as not received until its TPDOs come again.
  void reconfigure(std::size_t i, TimeNs now) noexcept;
  const Reconfiguration& reconfiguration(std::size_t i) const noexcept;
  // The controller's answer of the last transmit().
  const cia402::ControllerOutput& control(std::size_t i) const noexcept;

  const MasterCounters& counters() const noexcept;
  // Runtime SDO: non-RT code submits here, the cycle runs one transfer at a time.
  SdoQueue& sdo_queue() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace saw::canopen
