// The bridge (how components in other processes are reached and exported) as saw-rt loads it (from the
// package directory, like any lab's plug-in).
#include "saw/bridge/registration.hpp"
#include "saw/deploy/plugin.hpp"

SAW_PLUGIN(saw::bridge::register_components)
