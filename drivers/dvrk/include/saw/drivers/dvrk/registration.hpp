// The dVRK package's component type for deployments: `dvrk_arm`.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::drivers::dvrk {

// `dvrk_arm` (DvrkArm, an MTM or a PSM through the gateway's import of its topics) with its
// parameters' parser and its summary's format.
void register_components(deploy::ComponentRegistry& registry);

}  // namespace saw::drivers::dvrk
