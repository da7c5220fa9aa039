#include "saw/deploy/device_settings.hpp"

#include <cstdio>

namespace saw::deploy {

using namespace std::chrono_literals;
using ns = std::chrono::nanoseconds;

DeviceSettings parse_device_settings(const Params& p, const TaskConfig& task, const DeviceKeys& keys,
                                     DeviceSettings d) {
  const ns period = task.period;
  if (keys.force && p.has("max_force")) {
    d.max_force = p.get<double>("max_force");
    if (!(d.max_force > 0 && d.max_force <= keys.most_force)) {
      char b[96];
      std::snprintf(b, sizeof b, "must be in (0, %g] N (the most this device's hardware takes)",
                    keys.most_force);
      p.fail_at("max_force", b);
    }
  }
  d.command_timeout =
      p.get_duration_in("command_timeout", d.command_timeout > 0 ? ns(d.command_timeout) : 3 * period, period,
                        10s, "must be at least one period and at most 10 s");
  d.fault_on_command_timeout =
      p.get_enum<bool>("on_command_timeout", {{"hold", false}, {"fault", true}}, d.fault_on_command_timeout);
  d.start_enabled = p.get_or<bool>("start_enabled", d.start_enabled);
  if (keys.enable_timeout)
    d.enable_timeout = p.get_duration_in("enable_timeout", ns(d.enable_timeout), period, 60s,
                                         "must be at least one period and at most 60 s");
  if (keys.homes && p.has("home_timeout"))  // absent: the driver's (0: no limit here)
    d.home_timeout = p.get_duration_in("home_timeout", ns(d.home_timeout), period, 600s,
                                       "must be at least one period and at most 600 s");
  if ((keys.poses || keys.workspace) && p.has("workspace")) {
    const Params w = p.child("workspace");
    d.workspace_min = w.get<Vec3>("min");
    d.workspace_max = w.get<Vec3>("max");
    for (std::size_t k = 0; k < 3; ++k)
      if (!(d.workspace_min[k] < d.workspace_max[k])) w.fail_at("max", "must be above min on every axis");
  }
  if (keys.poses) {
    d.max_linear_speed = p.get_in_range("max_linear_speed", 1e-3, 2, d.max_linear_speed);
    d.max_angular_speed = p.get_in_range("max_angular_speed", 1e-3, 20, d.max_angular_speed);
  }
  return d;
}

}  // namespace saw::deploy
