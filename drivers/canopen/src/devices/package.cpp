// The canopen package as saw-rt loads it (from the package directory, like any lab's plug-in).
#include "saw/canopen/registration.hpp"
#include "saw/deploy/plugin.hpp"

SAW_PLUGIN(saw::canopen::register_components)
