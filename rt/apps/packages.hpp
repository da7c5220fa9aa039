// The package directory: where saw-rt finds the packages it loads, in-tree ones and a lab's alike.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "saw/deploy/registry.hpp"

namespace saw::apps {

// The directories searched: those of $SAW_PACKAGE_PATH (colon-separated) when it is set, else the
// package directory of this installation (<prefix>/<libdir>/sawrt/packages beside bin/, or the
// build tree's lib/sawrt/packages).
std::vector<std::filesystem::path> package_directories();

// Loads every package module (lib*.so) of those directories, in name order, as plug-ins (their
// types' origin is the module's path). Throws std::runtime_error naming the module, or saying
// where it looked when it found no package directory.
void load_packages(deploy::ComponentRegistry& registry);

}  // namespace saw::apps
