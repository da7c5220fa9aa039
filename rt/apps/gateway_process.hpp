// The saw-gateway process of a deployment, started and stopped by the saw-rt host.
#pragma once

#include <memory>

#include "saw/deploy/deployment.hpp"

namespace saw::apps {

// Starts saw-gateway (beside saw-rt's own executable) for `spec`; with mirrors or imports, waits
// until each is presented in this host's bridge (found by one of `registry`'s resolvers). The
// handle sends SIGTERM and waits when released.
std::shared_ptr<void> launch_gateway(const deploy::GatewaySpec& spec,
                                     const deploy::ComponentRegistry& registry);

}  // namespace saw::apps
