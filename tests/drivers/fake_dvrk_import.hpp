// FakeImport: a scripted stand-in for the gateway's import of a dVRK arm (its "dvrk" interface),
// playing the dVRK's operating-state machine and recording what reached it.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "saw/component.hpp"
#include "saw/crtk_arm.hpp"

namespace saw::drivers::dvrk::testing {

// What the import serves of a dVRK 2.x arm, played as the dVRK's state machine does (its
// operating_state: DISABLED → enable → busy while powering → ENABLED; home only when ENABLED,
// busy while homing), recording every command that reached it, with the arm's state then.
class FakeImport : public Component {
 public:
  struct Received {
    std::string_view what;  // "enable", "home", "disable", "servo_cf", "servo_cp", "jaw_servo_jp", "hold",
                            // "servo_jp", "move_cp", "move_jp", "free"
    OperatingState arm;
    Wrench wrench{};
    Pose pose{};
    double jaw = 0;
    JointState joints{};
  };

  explicit FakeImport(std::string name) : Component(std::move(name)) {
    namespace arm = crtk::arm;
    auto& p = provide("dvrk");
    crtk::provide(p, arm::measured_cp, state_table(), &cp_);
    crtk::provide(p, arm::measured_cv, state_table(), &cv_);
    crtk::provide(p, arm::operating_state, state_table(), &state_);
    crtk::provide(p, arm::servo_cf, [this](const Wrench& w) {
      got({"servo_cf", state, w, {}});
      wrench = w;  // the dVRK applies the last wrench for ever
    });
    crtk::provide(p, arm::servo_cp, [this](const Pose& x) {
      got({"servo_cp", state, {}, x});
      if (follows) pose = x;  // a PSM reaches its servo goal by its next sample
    });
    crtk::provide(p, arm::state_command, [this](const StateCommand& c) { command(c); });
    crtk::provide(p, arm::jaw_servo_jp, [this](const JointState& j) {
      Received r{"jaw_servo_jp", state, {}, {}};
      r.jaw = j.position[0];
      got(r);
    });
    // An MTM's gripper and a PSM's jaw: one joint each, `jaw` below.
    crtk::provide(p, arm::gripper_measured_js, state_table(), &jaw_js_);
    crtk::provide(p, arm::jaw_measured_js, state_table(), &jaw_js_);
    p.add_command_void("hold", [this] {
      got({"hold", state, {}, {}});
      wrench = {};
    });
    p.add_command_void("free", [this] {
      got({"free", state, {}, {}});
      wrench = {};
    });
    crtk::provide(p, arm::move_cp, [this](const Pose& x) { got({"move_cp", state, {}, x}); });
    const auto joints = [this](std::string_view what) {
      return [this, what](const JointState& j) {
        Received r{what, state, {}, {}};
        r.joints = j;
        got(r);
      };
    };
    crtk::provide(p, arm::move_jp, joints("move_jp"));
    crtk::provide(p, arm::servo_jp, joints("servo_jp"));
    crtk::provide(p, arm::measured_js, state_table(), &js_);
    crtk::provide(p, arm::measured_cf, state_table(), &cf_);
    p.add_command_read("errors", state_table().add_column("errors", &errors_));
    clutch_ = &crtk::provide(p, arm::clutch);
  }

  // One sample of the arm as the import would have it at t (the dVRK publishing).
  void publish(TimeNs t) {
    if (powering_ > 0 && --powering_ == 0) state = {OperatingStateValue::enabled, state.is_homed, false};
    if (homing_ > 0 && --homing_ == 0) state = {OperatingStateValue::enabled, true, false};
    cp_ = pose;
    state_ = state;
    errors_ = errors;
    jaw_js_.size = 1;
    jaw_js_.position[0] = jaw;
    js_ = js;
    cf_ = cf;
    state_table().advance(t);
  }
  // The console's clutch pedal, as the import passes it on.
  void clutch(bool pressed) { (void)(*clutch_)(ButtonEvent{pressed}); }
  int count(std::string_view what) const {
    for (std::size_t i = 0; i < kinds.size(); ++i)
      if (kinds[i] == what) return counts[i];
    return -1;
  }

  OperatingState state{OperatingStateValue::disabled, false, false};
  Pose pose{};
  int power_cycles = 5, home_cycles = 10;
  std::uint64_t errors = 0;     // error messages the arm sent (the import counts them)
  double jaw = 0.5;             // the gripper's or the jaw's angle, rad
  Wrench wrench{};              // what the arm applies: the last servo_cf (zeroed by hold)
  JointState js{};              // measured_js
  Wrench cf{};                  // measured_cf
  bool follows = true;          // measured_cp is the last servo_cp goal
  int lose_state_commands = 0;  // the next n state commands never reach the arm
  bool record = true;           // every command kept (allocates); off, only counted (the RT guard's runs)
  std::vector<Received> received;

 private:
  static constexpr std::array<std::string_view, 11> kinds{"enable",   "home",    "other",        "servo_cf",
                                                          "servo_cp", "hold",    "jaw_servo_jp", "servo_jp",
                                                          "move_cp",  "move_jp", "free"};
  std::array<int, kinds.size()> counts{};
  void got(const Received& r) {
    for (std::size_t i = 0; i < kinds.size(); ++i)
      if (kinds[i] == r.what) ++counts[i];
    if (record) received.push_back(r);
  }
  void command(StateCommand c) {
    got({c == StateCommand::enable ? "enable" : c == StateCommand::home ? "home" : "other", state, {}, {}});
    if (lose_state_commands > 0) {
      --lose_state_commands;  // lost on its way (a reader that was gone)
      return;
    }
    if (c == StateCommand::enable && state.state != OperatingStateValue::enabled) {
      state.is_busy = true;
      powering_ = power_cycles;
    }
    // The dVRK homes only an ENABLED arm (its ValidCommand table).
    if (c == StateCommand::home && state.state == OperatingStateValue::enabled) {
      state.is_busy = true;
      homing_ = home_cycles;
    }
  }
  int powering_ = 0, homing_ = 0;
  Pose cp_{};
  Twist cv_{};
  OperatingState state_{};
  std::uint64_t errors_ = 0;
  JointState jaw_js_{}, js_{};
  Wrench cf_{};
  EventWrite<ButtonEvent>* clutch_ = nullptr;
};

}  // namespace saw::drivers::dvrk::testing
