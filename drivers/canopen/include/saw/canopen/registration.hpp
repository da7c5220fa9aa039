// The CANopen package's component types for deployments: canopen_drive and canopen_arm.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::canopen {

// `canopen_drive` (one CiA 402 drive, CRTK joint commands) and `canopen_arm` (several drives on
// one bus, each a joint of a kinematic chain: the CRTK arm), each with its parameters' parser,
// and the format of their summary column (CanopenStatus). See drivers/canopen/README.md.
void register_components(deploy::ComponentRegistry& registry);

}  // namespace saw::canopen
