// The configuration of an attachment to the bus at a URI (the master's, the listener's).
#pragma once

#include <string>

#include "saw/can/bus.hpp"

namespace saw::bench::can_bench {

inline can::BusConfig bus_config(const std::string& uri) {
  can::BusConfig c;
  c.uri = uri;
  return c;
}

}  // namespace saw::bench::can_bench
