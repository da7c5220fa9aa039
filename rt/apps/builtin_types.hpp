// The component types saw-rt knows: simulated devices, teleoperation, delay.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::apps {

void register_builtin_types(deploy::ComponentRegistry& registry);

}  // namespace saw::apps
