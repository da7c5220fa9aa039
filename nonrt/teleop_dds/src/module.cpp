// The teleop package's mapping module, as saw-gateway and sawctl load it (lib/sawrt/mappings).
#include "saw/gateway/mapping_plugin.hpp"
#include "saw/teleop/dds/mappings.hpp"

SAW_MAPPINGS(saw::teleop::dds::register_mappings)
