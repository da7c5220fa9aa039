// The dvrk package as saw-rt loads it (from the package directory, like any lab's plug-in).
#include "saw/deploy/plugin.hpp"
#include "saw/drivers/dvrk/registration.hpp"

SAW_PLUGIN(saw::drivers::dvrk::register_components)
