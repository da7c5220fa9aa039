// A plug-in built for another plug-in ABI version: saw-rt must refuse it, naming both versions.
#include <cstdint>

#include "saw/deploy/plugin.hpp"

extern "C" __attribute__((visibility("default"))) std::uint32_t saw_plugin_abi_version() {
  return saw::deploy::plugin_abi_version + 1;
}

extern "C" __attribute__((visibility("default"))) void saw_plugin_register(saw::deploy::ComponentRegistry&) {
  __builtin_trap();  // never called: the version is checked first
}
