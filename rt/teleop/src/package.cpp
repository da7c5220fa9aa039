// The teleop package as saw-rt loads it (from the package directory, like any lab's plug-in).
#include "saw/deploy/plugin.hpp"
#include "saw/teleop/registration.hpp"

SAW_PLUGIN(saw::teleop::register_components)
