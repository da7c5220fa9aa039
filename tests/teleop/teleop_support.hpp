// What the teleop tests share: the rig with an Operator, its basic configuration, distances.
#pragma once

#include <cmath>
#include <vector>

#include "saw/testing/teleop_rig.hpp"

namespace saw::testing {

using TeleopConfig = CollaborativeTeleopConfig;

inline double norm(const saw::Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }
inline double dist(const saw::Vec3& a, const saw::Vec3& b) {
  return norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]});
}

// Lets the test call the teleop's provided "teleop" interface from its own thread.
class Operator : public saw::Component {
 public:
  Operator() : Component("operator") {
    auto& r = require("teleop");
    r.add_function("state_command", state_command);
    r.add_function("set_scale", set_scale);
    r.add_function("set_gains", set_gains);
    r.add_function("set_prediction", set_prediction);
    r.add_function("set_force_limits", set_force_limits);
    r.add_function("set_slave_offset", set_slave_offset);
    r.add_function("set_offset_limits", set_offset_limits);
    r.add_function("operating_state", operating_state);
    r.add_function("fault", fault);
    r.add_event_handler_write<saw::teleop::FaultInfo>(
        "fault", [this](const saw::teleop::FaultInfo& f) { fault_events.push_back(f); });
  }
  saw::FunctionWrite<saw::StateCommand> state_command;
  saw::FunctionWrite<double> set_scale;
  saw::FunctionWrite<saw::teleop::Gains> set_gains;
  saw::FunctionWrite<saw::teleop::Prediction> set_prediction;
  saw::FunctionWrite<saw::teleop::ForceLimits> set_force_limits;
  saw::FunctionWrite<saw::Vec3> set_slave_offset;
  saw::FunctionWrite<saw::teleop::OffsetLimits> set_offset_limits;
  saw::FunctionRead<saw::OperatingState> operating_state;
  saw::FunctionRead<saw::teleop::FaultInfo> fault;
  std::vector<saw::teleop::FaultInfo> fault_events;
};

using Rig = TeleopRig<Operator>;

inline TeleopConfig basic() {
  TeleopConfig c;
  c.gains = {100, 100};
  c.limits = {3, 3};
  return c;
}

}  // namespace saw::testing
