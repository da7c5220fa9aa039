// The teleoperation package's value types over DDS, registered by the package that owns them.
#pragma once

#include "saw/gateway/type_map.hpp"

namespace saw::teleop::dds {

// One line per type: Gains and ForceLimits (set_gains, set_force_limits, their read-backs) as
// saw_msgs/MasterSlave.
void register_mappings(gateway::MappingRegistry& registry);

}  // namespace saw::teleop::dds
