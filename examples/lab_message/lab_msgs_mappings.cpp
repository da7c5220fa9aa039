// The lab's message types over DDS: one line per type, in a mapping module saw-gateway and sawctl
// load (from $SAW_MAPPING_PATH, or <libdir>/sawrt/mappings once installed there).
#include <saw/gateway/fields_conversion.hpp>
#include <saw/gateway/mapping_plugin.hpp>

#include "lab_msgs/msg/SpringParamsPubSubTypes.h"
#include "spring_params.hpp"

namespace lab {

void register_mappings(saw::gateway::MappingRegistry& registry) {
  registry.add_fields<SpringParams, lab_msgs::msg::SpringParamsPubSubType>();
}

}  // namespace lab

SAW_MAPPINGS(lab::register_mappings)
