#include "saw/bridge/registration.hpp"

#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"

namespace saw::bridge {

void register_components(deploy::ComponentRegistry& registry) {
  registry.add_resolver([] { return std::make_unique<ShmResolver>(); });
  registry.set_exporter([](Component& c, const std::string& provided) -> std::shared_ptr<void> {
    return std::make_shared<Exporter>(c, provided);
  });
}

}  // namespace saw::bridge
