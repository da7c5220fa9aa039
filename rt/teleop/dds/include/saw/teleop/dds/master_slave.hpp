// MasterSlaveConv: a teleoperation setting with one number per side, as saw_msgs/MasterSlave.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "saw/gateway/typed_mapping.hpp"
#include "saw_msgs/msg/MasterSlave.h"

namespace saw::teleop::dds {

// teleop::Gains, teleop::ForceLimits (any T with double master, slave); text "MASTER SLAVE".
template <class T>
struct MasterSlaveConv {
  static void each(const T& v, std::vector<double>& o) { o.insert(o.end(), {v.master, v.slave}); }
  static void to_msg(const T& v, saw_msgs::msg::MasterSlave& m) {
    m.master(v.master);
    m.slave(v.slave);
  }
  static bool from_msg(const saw_msgs::msg::MasterSlave& m, T& v, std::string& why) {
    if (!std::isfinite(m.master()) || !std::isfinite(m.slave())) {
      why = "master or slave is not finite";
      return false;
    }
    v.master = m.master();
    v.slave = m.slave();
    return true;
  }
  static std::string text(const T& v) {
    char b[64];
    std::snprintf(b, sizeof b, "master %.6g slave %.6g", v.master, v.slave);
    return b;
  }
  static bool parse(std::string_view t, T& v, std::string& why) {
    const auto n = gateway::convert::numbers(t, why);
    if (!gateway::convert::count_is(n, {2}, why)) return false;
    v.master = n[0];
    v.slave = n[1];
    return true;
  }
};

}  // namespace saw::teleop::dds
