// The Falcon package's component type for deployments: `falcon`.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::drivers::falcon {

// `falcon` (FalconDevice over USB or the simulated firmware) with its parameters' parser and
// its summary's format.
void register_components(deploy::ComponentRegistry& registry);

}  // namespace saw::drivers::falcon
