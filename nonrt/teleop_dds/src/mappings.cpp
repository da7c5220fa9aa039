#include "saw/teleop/dds/mappings.hpp"

#include "saw/gateway/fields_conversion.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/offset_trajectory.hpp"
#include "saw/teleop/teleop_law.hpp"
#include "saw_msgs/msg/MasterSlavePubSubTypes.h"
#include "saw_msgs/msg/OffsetLimitsPubSubTypes.h"
#include "saw_msgs/msg/PredictionPubSubTypes.h"

namespace saw::teleop::dds {

void register_mappings(gateway::MappingRegistry& registry) {
  // Both on one message type (master, slave): a lookup by DDS type finds Gains, whose layout
  // ForceLimits shares, so the bytes are the same either way.
  registry.add_fields<Gains, saw_msgs::msg::MasterSlavePubSubType>();
  registry.add_fields<ForceLimits, saw_msgs::msg::MasterSlavePubSubType>();
  registry.add_fields<OffsetLimits, saw_msgs::msg::OffsetLimitsPubSubType>();
  registry.add_fields<Prediction, saw_msgs::msg::PredictionPubSubType>();
}

}  // namespace saw::teleop::dds
