#include "saw/can/bus.hpp"

#include <stdexcept>

#include "saw/can/socketcan_bus.hpp"
#include "saw/can/virtual_bus.hpp"

namespace saw::can {

std::string_view to_string(BusState s) noexcept {
  switch (s) {
    case BusState::error_active:
      return "error-active";
    case BusState::error_warning:
      return "error-warning";
    case BusState::error_passive:
      return "error-passive";
    case BusState::bus_off:
      return "bus-off";
    case BusState::down:
      return "down";
  }
  return "unknown";
}

std::unique_ptr<Bus> open_bus(const BusConfig& config) {
  const std::string_view uri = config.uri;
  if (uri.starts_with("socketcan:")) return std::make_unique<SocketCanBus>(config);
  if (uri.starts_with("virtual:")) return std::make_unique<VirtualBus>(config, uri.substr(8));
  throw std::runtime_error("CAN bus '" + config.uri + "': expected socketcan:<ifname> or virtual:<name>");
}

}  // namespace saw::can
