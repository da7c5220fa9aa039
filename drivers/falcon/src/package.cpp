// The falcon package as saw-rt loads it (from the package directory, like any lab's plug-in).
#include "saw/deploy/plugin.hpp"
#include "saw/drivers/falcon/registration.hpp"

SAW_PLUGIN(saw::drivers::falcon::register_components)
