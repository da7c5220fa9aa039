// FakeDevice: a passive CRTK device whose state the test sets and publishes explicitly.
#pragma once

#include "saw/component.hpp"
#include "saw/crtk.hpp"
#include "saw/manager.hpp"

namespace saw::testing {

class FakeDevice : public Component {
 public:
  explicit FakeDevice(std::string name) : Component(std::move(name)) {
    auto& p = provide("arm");
    p.add_command_read("measured_cp", state_table().add_column("measured_cp", &pose_));
    p.add_command_read("measured_cv", state_table().add_column("measured_cv", &twist_));
    p.add_command_write<Wrench>("servo_cf", [this](const Wrench& w) {
      force = w.force;
      ++commands;
    });
    clutch_ = &p.add_event_write<ButtonEvent>("clutch");
  }
  // Publishes the current position and velocity as a row stamped t (what a device cycle does).
  void publish(TimeNs t) {
    pose_.position = position;
    twist_.linear = velocity;
    state_table().advance(t);
  }
  void press_clutch(bool pressed) { (void)(*clutch_)(ButtonEvent{pressed}); }

  Vec3 position{}, velocity{}, force{};
  int commands = 0;

 private:
  Pose pose_;
  Twist twist_;
  EventWrite<ButtonEvent>* clutch_;
};

// Steps a stepped manager by one 1 ms period, publishing the devices first unless frozen.
struct Stepper {
  Manager& manager;
  TimeNs next = 0;
  void operator()(std::initializer_list<FakeDevice*> publish) {
    for (auto* d : publish) d->publish(next);
    manager.step_until(next);
    next += 1'000'000;
  }
};

}  // namespace saw::testing
