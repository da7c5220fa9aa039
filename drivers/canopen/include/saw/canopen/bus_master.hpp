// The CANopen master of one bus, run by one periodic RT task: frames in, CiA 402 drives, RPDOs and SYNC out.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/axis.hpp"
#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/node_driver.hpp"
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

// Its counters are a node driver's (node_driver.hpp).
using MasterCounters = NodeCounters;

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
class BusMaster : public NodeDriver {
 public:
  // Throws std::invalid_argument naming the axis and the problem (see check(AxisConfig)), and
  // for two axes that share a node-ID or a PDO identifier.
  BusMaster(can::Bus& bus, BusMasterConfig config, std::vector<AxisConfig> axes);
  ~BusMaster() override;

  const AxisConfig& axis(std::size_t i) const noexcept;
  const AxisFeedback& feedback(std::size_t i) const noexcept;

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

  // The last frames of a master that stops: every drive's RPDOs with `controlword` (disable
  // voltage, or quick stop) and the setpoints as set, one SYNC so that the drives take them at
  // once, then NMT enter pre-operational for every node. Sent before it returns.
  void shut_down(std::uint16_t controlword, TimeNs now) noexcept;
  // reconfigure(i, now) (NodeDriver): its feedback also counts as not valid until its TPDOs come
  // again, and stale from the re-configuration's end.
  // The controller's answer of the last transmit().
  const cia402::ControllerOutput& control(std::size_t i) const noexcept;

 private:
  void on_first_cycle(TimeNs now) noexcept override;
  void on_received(std::size_t i, TimeNs now) noexcept override;
  void before_rpdos(std::size_t i, TimeNs now) noexcept override;
  void after_rpdos(TimeNs now) noexcept override;
  void before_shut_down(std::size_t i, TimeNs now) noexcept override;
  can::Frame shut_down_sync() noexcept override;
  void on_reconfigure(std::size_t i) noexcept override;
  void on_reconfigured(std::size_t i, TimeNs now) noexcept override;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace saw::canopen
