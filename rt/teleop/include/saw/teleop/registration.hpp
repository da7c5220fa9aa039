// The teleoperation package's component types for deployments: teleop, delay.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::teleop {

// `teleop` (Teleoperation, running a law of laws(registry)) and `delay` (DelayTask), each with its
// parameters' parser, and the teleop summary's format.
void register_components(deploy::ComponentRegistry& registry);

}  // namespace saw::teleop
