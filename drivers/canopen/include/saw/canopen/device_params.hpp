// The deployment keys every CANopen device type shares, each read once with one range (file:line:key).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "saw/canopen/axis.hpp"
#include "saw/canopen/cia402.hpp"
#include "saw/canopen/eds.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/clock.hpp"
#include "saw/deploy/params.hpp"

namespace saw::canopen {

// `master_heartbeat: {node, period, timeout}`: the master's node-ID, how often it beats, and how
// long each node's consumer (0x1016) waits for it (0: the nodes do not watch it).
struct MasterHeartbeatParams {
  std::uint8_t node = 127;
  TimeNs period = 100'000'000;
  TimeNs timeout = 300'000'000;
};

// What a CANopen device's section says beside its own hardware: its bus, its nodes' heartbeat,
// the master's (a device alone on its bus sends it; on a shared bus it is the bus task's), the
// RPDO deadline, how old its feedback may be and the start-up's timeouts.
struct NodeParams {
  std::string bus;               // a URI (alone on its bus) or the name of a canopen_bus component
  TimeNs heartbeat_period = 0;   // 0x1017 of each node
  TimeNs heartbeat_timeout = 0;  // a node is lost after this long without one
  MasterHeartbeatParams master;
  std::optional<TimeNs> rpdo_deadline;  // absent: the component's default (resolve_rpdo_deadline)
  TimeNs feedback_timeout = 0;
  StartupConfig startup;
};

namespace params {
// The shared keys for a device whose task runs every `period`: `bus`, `heartbeat: {period,
// timeout}`, `master_heartbeat` (only with a URI: on a shared bus it is the bus task's),
// `rpdo_deadline`, `feedback_timeout`, `startup: {boot_timeout, sdo_timeout, operational_timeout}`.
NodeParams parse_node(const deploy::Params& p, TimeNs period);
MasterHeartbeatParams parse_master_heartbeat(const deploy::Params& p);
// `bus:`: a URI, or the name of a canopen_bus component.
std::string parse_bus(const deploy::Params& p);
// `rpdo_deadline: 5ms` (rounded up to whole ms, at least two periods), `off` or 0: not watched;
// absent: nullopt.
std::optional<TimeNs> rpdo_deadline(const deploy::Params& p, TimeNs period);
// `pdo: {rpdo1: [...], tpdo2: [...]}` or `eds: file` (its identity too, and the parsed file in
// `eds` if given); neither: the CiA 402 defaults for `mode`.
std::vector<PdoMapping> parse_pdos(const deploy::Params& p, cia402::Mode mode, std::uint8_t node,
                                   const std::string& directory, std::optional<DriveIdentity>& identity,
                                   std::optional<Eds>* eds = nullptr);
// `sdo: ["0x60C2:01:u8=10", ...]`: the deployment's own start-up writes.
std::vector<SdoWrite> parse_writes(const deploy::Params& p);
}  // namespace params

// Puts the shared keys where a device's configuration keeps them under the in-tree names (bus,
// master_node, master_heartbeat_period/timeout, rpdo_deadline, feedback_timeout, startup); the
// nodes' heartbeat is the caller's to place (an arm's drives share one, an I/O node has its own).
template <class Config>
void apply_node_params(const NodeParams& n, Config& c) {
  c.bus = n.bus;
  c.master_node = n.master.node;
  c.master_heartbeat_period = n.master.period;
  c.master_heartbeat_timeout = n.master.timeout;
  c.rpdo_deadline = n.rpdo_deadline;
  c.feedback_timeout = n.feedback_timeout;
  c.startup = n.startup;
}

}  // namespace saw::canopen
