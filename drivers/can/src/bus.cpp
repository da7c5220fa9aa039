#include "saw/can/bus.hpp"

#include <stdexcept>

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
  throw std::runtime_error("CAN bus '" + config.uri + "': no backend is built yet");
}

}  // namespace saw::can
