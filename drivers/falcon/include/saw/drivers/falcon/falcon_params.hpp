// The `falcon` component's parameters: the config structs and the parser, next to each other.
#pragma once

#include <string>

#include "saw/deploy/params.hpp"
#include "saw/deploy/registry.hpp"
#include "saw/drivers/falcon/falcon_device.hpp"
#include "saw/drivers/falcon/sim_firmware.hpp"
#include "saw/drivers/falcon/usb_transport.hpp"

namespace saw::drivers::falcon {

enum class TransportKind : std::uint8_t { usb, sim };

// Everything a deployment says about one Falcon.
struct FalconSpec {
  TaskConfig task;
  FalconConfig device;
  TransportKind transport = TransportKind::usb;
  UsbConfig usb;          // transport: usb (firmware, bus, index, exchange_timeout)
  SimFirmwareConfig sim;  // transport: sim (hand script, dynamics)
  // The exchanges in an I/O thread beside the task (ThreadedTransport): the default on USB,
  // whose transfers may wait longer than a period and allocate inside libusb.
  bool io_thread = false;
  int io_priority = 0;   // SCHED_FIFO; default: the task's priority + 1 (0 stays 0)
  TimeNs reconnect = 0;  // ns between looks for an unplugged Falcon (default 1 s with io_thread)
};

// params: the device base's (deploy/device_settings.hpp: max_force up to 20 N, workspace, home_timeout,
// command_timeout, on_command_timeout, start_enabled, enable_timeout), transport (usb|sim), io_thread,
// io_priority, reconnect, firmware, usb: {bus, index, exchange_timeout_ms, handshake_tries,
// load_attempts}, origin, home_on_start, homing_dac, max_missed, clutch_buttons, operator_buttons,
// calibration: {dac_per_newton_metre, dac_limit, angle_at_zero}, sim: {initial_angles,
// operator_homes, inertia, damping, hand: {amplitude, frequency, stiffness, damping}}. Errors name file:line
// and the key (deploy::Params).
FalconSpec parse_falcon(const deploy::ComponentContext& ctx, deploy::Params& p);

// The transport the spec names (not opened).
std::unique_ptr<FalconTransport> make_transport(const FalconSpec& s);

}  // namespace saw::drivers::falcon
