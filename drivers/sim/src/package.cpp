// The sim package as saw-rt loads it (from the package directory, like any lab's plug-in).
#include "saw/deploy/plugin.hpp"
#include "saw/drivers/sim_registration.hpp"

SAW_PLUGIN(saw::drivers::sim::register_components)
