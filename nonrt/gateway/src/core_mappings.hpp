// The rt core's own types (CRTK values, numbers, task statistics, descriptions) as the gateway maps them.
#pragma once

#include "saw/gateway/type_map.hpp"

namespace saw::gateway {

// One line per type; a package maps its own types in its mapping module (mapping_plugin.hpp).
void register_core_mappings(MappingRegistry& r);

}  // namespace saw::gateway
