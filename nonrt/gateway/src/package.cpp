// The gateway package as saw-rt loads it: the deployment's `gateway:` section and its process.
#include "saw/deploy/plugin.hpp"
#include "saw/gateway/settings.hpp"

namespace {
void register_gateway(saw::deploy::ComponentRegistry& registry) {
  saw::gateway::register_components(registry);
}
}  // namespace

SAW_PLUGIN(register_gateway)
