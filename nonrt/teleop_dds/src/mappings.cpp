#include "saw/teleop/dds/mappings.hpp"

#include "saw/gateway/fields_conversion.hpp"
#include "saw/teleop/teleop_law.hpp"
#include "saw_msgs/msg/MasterSlavePubSubTypes.h"

namespace saw::teleop::dds {

void register_mappings(gateway::MappingRegistry& registry) {
  // Both on one message type (master, slave): a lookup by DDS type finds Gains, whose layout
  // ForceLimits shares, so the bytes are the same either way.
  registry.add_fields<Gains, saw_msgs::msg::MasterSlavePubSubType>();
  registry.add_fields<ForceLimits, saw_msgs::msg::MasterSlavePubSubType>();
}

}  // namespace saw::teleop::dds
