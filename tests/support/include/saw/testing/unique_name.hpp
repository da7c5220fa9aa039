// unique_name: a name no other test process running at the same time uses.
#pragma once

#include <unistd.h>

#include <string>
#include <string_view>

namespace saw::testing {

// `prefix` and this process's id: components, their /saw.<name> segments and DDS names of test
// binaries running side by side (ctest -j) do not collide.
inline std::string unique_name(std::string_view prefix) {
  return std::string(prefix) + std::to_string(getpid());
}

}  // namespace saw::testing
