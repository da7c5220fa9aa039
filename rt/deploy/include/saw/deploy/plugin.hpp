// Plug-in entry points: how a shared library adds its component types to saw-rt.
#pragma once

#include <cstdint>

#include "saw/deploy/registry.hpp"

namespace saw::deploy {

// Bumped whenever a change to the core or deploy libraries means a plug-in built against the
// old headers would misbehave (class layouts, virtual functions, the registry's API). saw-rt
// refuses a plug-in whose version differs, naming both.
inline constexpr std::uint32_t plugin_abi_version =
    6;  // 3: saw::Device; 4: LawModel::describe; 5: LawModel::wave_impedance; 6: TaskConfig::history, servo_cp

}  // namespace saw::deploy

// In one source file of a plug-in:
//   SAW_PLUGIN(my_lab::register_components)
// where `void my_lab::register_components(saw::deploy::ComponentRegistry&)` adds its types.
// A deployment loads it with `plugins: [path/to/libmy_lab.so]`.
#define SAW_PLUGIN(register_function)                                                        \
  extern "C" __attribute__((visibility("default"))) std::uint32_t saw_plugin_abi_version() { \
    return ::saw::deploy::plugin_abi_version;                                                \
  }                                                                                          \
  extern "C" __attribute__((visibility("default"))) void saw_plugin_register(                \
      ::saw::deploy::ComponentRegistry& registry) {                                          \
    register_function(registry);                                                             \
  }
