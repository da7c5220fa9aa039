// The simulated-device package's component types for deployments: sim_haptic_device.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::drivers::sim {

// `sim_haptic_device` (SimHapticDevice) with its parameters' parser and its summary's format.
void register_components(deploy::ComponentRegistry& registry);

}  // namespace saw::drivers::sim
