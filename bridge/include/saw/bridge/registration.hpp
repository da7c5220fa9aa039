// The bridge's part in deployments: reaching components of other processes, exporting ours.
#pragma once

#include "saw/deploy/registry.hpp"

namespace saw::bridge {

// The shared-memory resolver (connect() finds servers exported by other processes of this
// host) and the exporter (a deployment's `exports:`).
void register_components(deploy::ComponentRegistry& registry);

}  // namespace saw::bridge
