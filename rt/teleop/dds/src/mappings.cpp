#include "saw/teleop/dds/mappings.hpp"

#include "saw/teleop/dds/master_slave.hpp"
#include "saw/teleop/teleop_law.hpp"
#include "saw_msgs/msg/MasterSlavePubSubTypes.h"

namespace saw::teleop::dds {

void register_mappings(gateway::MappingRegistry& registry) {
  // Both on one message type: a lookup by DDS type finds Gains, whose layout ForceLimits shares
  // (two doubles, master then slave), so the bytes are the same either way.
  registry.add<Gains, saw_msgs::msg::MasterSlavePubSubType, MasterSlaveConv<Gains>>();
  registry.add<ForceLimits, saw_msgs::msg::MasterSlavePubSubType, MasterSlaveConv<ForceLimits>>();
}

}  // namespace saw::teleop::dds
