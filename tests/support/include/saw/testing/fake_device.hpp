// FakeDevice: a passive CRTK device whose state the test sets and publishes explicitly.
#pragma once

#include <cmath>
#include <string>
#include <utility>

#include "saw/component.hpp"
#include "saw/crtk.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/manager.hpp"

namespace saw::testing {

class FakeDevice : public Component {
 public:
  // takes_moves: it provides move_cp (recorded, not acted on: the test moves it).
  explicit FakeDevice(std::string name, bool takes_moves = true) : Component(std::move(name)) {
    namespace arm = crtk::arm;
    auto& p = provide(std::string(arm::interface_name));
    crtk::provide(p, arm::measured_cp, state_table(), &pose_);
    crtk::provide(p, arm::measured_cv, state_table(), &twist_);
    crtk::provide(p, arm::servo_cf, [this](const Wrench& w) {
      force = w.force;
      ++commands;
    });
    crtk::provide(p, arm::servo_cp, [this](const Pose& x) {
      goal = x;
      ++goals;
    });
    if (takes_moves)
      crtk::provide(p, arm::move_cp, [this](const Pose& x) {
        move_goal = x;
        ++moves;
      });
    // A gripper (as a master's) and a jaw (as a slave's): `grip`, NaN for a device without.
    crtk::provide(p, arm::gripper_measured_js, state_table(), &grip_js_);
    crtk::provide(p, arm::jaw_measured_js, state_table(), &grip_js_);
    crtk::provide(p, arm::jaw_servo_jp, [this](const JointState& j) {
      jaw_goal = j.size >= 1 ? j.position[0] : std::nan("");
      ++jaw_goals;
    });
    clutch_ = &crtk::provide(p, arm::clutch);
    operator_ = &crtk::provide(p, arm::operator_present);
    crtk::provide(p, arm::operating_state, state_table(), &state_);
    p.add_command_read("watchdog_trips", state_table().add_column("watchdog_trips", &trips_));
    crtk::provide(p, arm::measured_cf, state_table(), &wrench_);
  }
  // Publishes the current position and velocity as a row stamped t (what a device cycle does).
  void publish(TimeNs t) {
    pose_.position = position;
    pose_.orientation = orientation;
    twist_.linear = velocity;
    state_.state = operating;
    state_.is_busy = busy;
    grip_js_.size = std::isnan(grip) ? 0 : 1;
    grip_js_.position[0] = std::isnan(grip) ? 0 : grip;
    trips_ = watchdog_trips;
    wrench_ = wrench;
    state_table().advance(t);
  }
  void press_clutch(bool pressed) { (void)(*clutch_)(ButtonEvent{pressed}); }
  void press_operator_present(bool pressed) { (void)(*operator_)(ButtonEvent{pressed}); }

  Vec3 position{}, velocity{}, force{};
  Quat orientation{0, 0, 0, 1};
  Pose goal{};  // the last servo_cp
  int goals = 0;
  Pose move_goal{};  // the last move_cp
  int moves = 0;
  OperatingStateValue operating = OperatingStateValue::enabled;
  bool busy = false;  // operating_state's is_busy (homing)
  int commands = 0;
  double grip = std::nan("");      // rad: the gripper's or the jaw's angle; NaN: none
  double jaw_goal = std::nan("");  // the last jaw_servo_jp
  int jaw_goals = 0;
  std::uint64_t watchdog_trips = 0;  // a device's: how often its commands stopped
  Wrench wrench{};                   // measured_cf (a force sensor's)

 private:
  Pose pose_;
  Twist twist_;
  JointState grip_js_{};
  OperatingState state_{OperatingStateValue::enabled, true, false};
  std::uint64_t trips_ = 0;
  Wrench wrench_{};
  EventWrite<ButtonEvent>* clutch_;
  EventWrite<ButtonEvent>* operator_;
};

}  // namespace saw::testing
