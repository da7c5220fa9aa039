// The device base's keys in a deployment file: parsed here once, for every driver.
#pragma once

#include "saw/deploy/params.hpp"
#include "saw/device.hpp"
#include "saw/task.hpp"

namespace saw::deploy {

// Which of the base's keys a driver's hardware takes, and the most its hardware takes. A key the
// driver does not take is left unread: in the file, it is an unknown key at its line.
struct DeviceKeys {
  bool force = true;           // max_force (a device taking servo_cf)
  double most_force = 1e5;     // N: the hardware's most; max_force above it is refused
  bool enable_timeout = true;  // enable_timeout (a driver whose enable has its own limits: false)
  bool homes = false;          // home_timeout
  bool poses = false;          // servo_cp: workspace, max_linear_speed, max_angular_speed
  bool workspace = false;      // workspace alone (the Falcon's force box)
};

// The base's keys read from `p` over the driver's `defaults`, each in its one range (the file,
// line and key named on an error):
//   max_force          (0, most_force] N
//   command_timeout    [one period, 10 s]; absent: 3 periods
//   on_command_timeout hold | fault
//   start_enabled      true | false
//   enable_timeout     [one period, 60 s]
//   home_timeout       [one period, 600 s]
//   workspace          {min: [x, y, z], max: [x, y, z]}, max above min on every axis
//   max_linear_speed   [0.001, 2] m/s;  max_angular_speed  [0.001, 20] rad/s
DeviceSettings parse_device_settings(const Params& p, const TaskConfig& task, const DeviceKeys& keys,
                                     DeviceSettings defaults);

}  // namespace saw::deploy
