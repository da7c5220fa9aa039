// What saw-can-sim runs: the bus, its cycle, the drives and the faults to inject, from YAML and the command
// line.
#pragma once

#include <string>
#include <vector>

#include "saw/canopen/sim/fault.hpp"
#include "saw/canopen/sim/sim_drive.hpp"
#include "saw/clock.hpp"

namespace saw::canopen::sim {

struct SimConfig {
  std::string bus;                     // virtual:<name> or socketcan:<ifname>
  TimeNs period = 250'000;             // the drives' cycle
  std::vector<SimDriveConfig> drives;  // distinct node-IDs
  std::vector<ScheduledFault> faults;  // each for one of the drives
};

// A file such as
//   bus: virtual:lab
//   period: 250us
//   drives:
//     - node: 1
//       eds: vendor.eds          # relative to this file; absent: the built-in sim_drive.eds
//       heartbeat_ms: 100
//       motor: {load_inertia: 0.2, viscous_friction: 1e-4, load_torque: 1.5}
//     - node: 2
//   faults: ["2:over-current:1.5", "1:bus-off:3:0.5"]
// Unknown keys, a bad value or a fault for a node that is not there throw
// saw::deploy::ConfigError naming file:line:column and the key.
SimConfig parse_sim_config(const std::string& yaml_text, const std::string& file);
SimConfig load_sim_config(const std::string& path);

// Set-up: throws std::invalid_argument for no drive, a node-ID twice, a fault for a node that is
// not simulated, or a period outside 50 µs .. 100 ms.
void check(const SimConfig& c);

}  // namespace saw::canopen::sim
