// Mapping modules: how a package adds the DDS mappings of its own types to saw-gateway and sawctl.
#pragma once

#include <cstdint>

#include "saw/gateway/type_map.hpp"

namespace saw::gateway {

// Bumped whenever Mapping, MappingRegistry or TypedMapping change so that a module built against
// the old headers would misbehave; a module of another version is refused, naming both.
inline constexpr std::uint32_t mapping_abi_version = 1;

}  // namespace saw::gateway

// In one source file of a package's mapping module (built with saw_mapping_module, or as a
// MODULE library installed in <libdir>/sawrt/mappings):
//   SAW_MAPPINGS(my_lab::register_mappings)
// where `void my_lab::register_mappings(saw::gateway::MappingRegistry&)` adds one line per type:
//   registry.add<my_lab::Spring, lab_msgs::msg::SpringPubSubType, SpringConv>();
#define SAW_MAPPINGS(register_function)                                                       \
  extern "C" __attribute__((visibility("default"))) std::uint32_t saw_mapping_abi_version() { \
    return ::saw::gateway::mapping_abi_version;                                               \
  }                                                                                           \
  extern "C" __attribute__((visibility("default"))) void saw_mapping_register(                \
      ::saw::gateway::MappingRegistry& registry) {                                            \
    register_function(registry);                                                              \
  }
