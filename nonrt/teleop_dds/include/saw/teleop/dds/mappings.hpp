// The teleoperation package's value types over DDS, registered by the package that owns them.
#pragma once

#include "saw/gateway/type_map.hpp"

namespace saw::teleop::dds {

// One line per type, each with its set_<name> command and read-back: Gains and ForceLimits as
// saw_msgs/MasterSlave, OffsetLimits as saw_msgs/OffsetLimits, Prediction as saw_msgs/Prediction.
void register_mappings(gateway::MappingRegistry& registry);

}  // namespace saw::teleop::dds
