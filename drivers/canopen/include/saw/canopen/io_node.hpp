// A generic CANopen I/O node as the master runs it: values out through its RPDOs, values in from its TPDOs,
// its health.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/axis.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/node_driver.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sdo_queue.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// A node with no profile the master knows (CiA 401 digital/analog I/O, a gripper's controller,
// a vendor's device): what it is sent and what it sends are the objects its PDOs map.
struct IoNodeConfig {
  std::string name;  // what faults and logs call it
  std::uint8_t node = 1;
  std::vector<PdoMapping> pdos;            // what the start-up configures (disabled ones: not valid)
  std::vector<PdoEntry> outputs;           // each mapped by an enabled RPDO: set_output() packs it
  std::vector<PdoEntry> inputs;            // each mapped by an enabled TPDO: input() reads it
  TimeNs heartbeat_period = 100'000'000;   // 0x1017
  TimeNs heartbeat_timeout = 300'000'000;  // lost after this long without one
  std::uint8_t master_node = 127;          // 0x1016:01: the master it watches ...
  TimeNs master_timeout = 300'000'000;     // ... and for how long (0: not watched)
  RpdoDeadline rpdo_deadline;              // its RPDOs' event timers (nullopt time: not written)
  std::vector<SdoWrite> writes;            // the deployment's own, after 0x1016
  std::optional<DriveIdentity> identity;   // 0x1000, 0x1018:01/02 as its EDS says; nullopt: not checked
};

// Set-up: throws std::invalid_argument naming the node and what is wrong (node-ID, heartbeat
// times, a PDO check() refuses, an output or input no enabled PDO of its kind maps).
void check(const IoNodeConfig& c);

// An I/O node's EMCYs by what they mean (node_driver.hpp).
using IoEmcys = NodeEmcys;

// Its start-up: PDOs, the RPDO deadline, 0x1017, 0x1016:01, the deployment's writes (no CiA 402 objects).
NodeSetup setup_of(const IoNodeConfig& c);

// The cycle, on the owner's thread (NodeDriver): receive() takes every frame that arrived
// (TPDOs, heartbeat, EMCY; anything else counted as foreign), transmit() sends the RPDOs with the
// outputs as set. Neither allocates, locks, blocks, prints nor throws. SYNC and the master's
// heartbeat are the bus task's.
class IoNode : public NodeDriver {
 public:
  IoNode(can::Bus& bus, IoNodeConfig config);  // throws as check()
  ~IoNode() override;

  const IoNodeConfig& config() const noexcept { return config_; }
  // Output i as its mapped type holds it (an integer: rounded); a value the type cannot hold is
  // not packed (the previous one stays) and the reason returned.
  Codec set_output(std::size_t i, double value) noexcept;
  // Input i from the last TPDO that carried it; false before one came.
  bool input(std::size_t i, double& value) const noexcept;
  bool valid() const noexcept { return tpdos_valid(0); }        // every enabled TPDO arrived at least once
  bool fresh() const noexcept { return NodeDriver::fresh(0); }  // a TPDO arrived in the last receive()
  TimeNs last_received() const noexcept { return NodeDriver::last_received(0); }  // when (the cycle's time)
  const AxisHealth& health() const noexcept { return NodeDriver::health(0); }     // heartbeat, NMT, EMCY, ...
  std::uint64_t foreign_frames() const noexcept { return counters().foreign_frames; }
  const IoEmcys& emcys() const noexcept { return NodeDriver::emcys(0); }
  // Starts running the node's configuration again (a node that rebooted: its PDOs, heartbeat and
  // consumer are gone): the start-up's SDO writes, NMT start, an operational heartbeat, stepped by
  // transmit(); its inputs count as not received until its TPDOs come again.
  void reconfigure(TimeNs now) noexcept { NodeDriver::reconfigure(0, now); }
  const Reconfiguration& reconfiguration() const noexcept { return NodeDriver::reconfiguration(0); }
  // Runtime SDO (sdo_queue()): requests for this node only, one transfer at a time through the
  // node's SDO channel (not while a re-configuration runs). shut_down(): the RPDOs with the
  // outputs as set (the caller set the safe ones), one SYNC so that the node takes them at once,
  // NMT enter pre-operational.

 private:
  IoNodeConfig config_;
  std::vector<MappedAt> outputs_, inputs_;  // where each output and input sits
};

}  // namespace saw::canopen
