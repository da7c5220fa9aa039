// canopen_bus and canopen_io for deployments (registration_bus.cpp; not installed).
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::canopen {

void register_bus_components(deploy::ComponentRegistry& registry);

}  // namespace saw::canopen
