// Teleoperation rigs: the teleoperation task between two fake devices, on the stepped clock.
#pragma once

#include <chrono>
#include <utility>

#include "saw/manager.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/stepper.hpp"

namespace saw::testing {

// The task's settings and the collaborative law's, in one: what most teleoperation tests set.
struct CollaborativeTeleopConfig : saw::teleop::TeleopConfig, saw::teleop::CollaborativeSettings {};

// Commanded by `Operator`, a component requiring "teleop" built from `operator_args`: the test
// chooses how it commands the teleoperation task (from its own thread, or from an RT task).
template <class Operator>
struct TeleopRig {
  template <class... OperatorArgs>
  explicit TeleopRig(const CollaborativeTeleopConfig& config, OperatorArgs&&... operator_args)
      : TeleopRig(static_cast<const saw::teleop::TeleopConfig&>(config),
                  saw::teleop::law_spec<saw::teleop::CollaborativeLaw>(config),
                  std::forward<OperatorArgs>(operator_args)...) {}
  // Any law.
  template <class... OperatorArgs>
  TeleopRig(const saw::teleop::TeleopConfig& config, const saw::teleop::LawSpec& law,
            OperatorArgs&&... operator_args)
      : teleop("teleop", TaskConfig::periodic(std::chrono::milliseconds(1), 0), config, law),
        op(std::forward<OperatorArgs>(operator_args)...) {
    manager.add(master);
    manager.add(slave);
    manager.add(teleop);
    manager.add(op);
    manager.connect("teleop", "master", "master", "arm");
    manager.connect("teleop", "slave", "slave", "arm");
    manager.connect(op.name(), "teleop", "teleop", "teleop");
    manager.start_stepped();
  }
  // n periods; a master that does not publish is one that went silent.
  void step(int n = 1, bool publish_master = true) {
    for (int i = 0; i < n; ++i) publish_master ? stepper({&master, &slave}) : stepper({&slave});
  }
  FakeDevice master{"master"}, slave{"slave"};
  saw::teleop::Teleoperation teleop;
  Operator op;
  Manager manager;
  Stepper stepper{manager};
};

// No operator; the master reaches the teleoperation task through "master_delay", `delay_s` late.
struct DelayedTeleopRig {
  DelayedTeleopRig(const CollaborativeTeleopConfig& config, double delay_s)
      : delay("master_delay", TaskConfig::periodic(std::chrono::milliseconds(1), 0), delay_s),
        teleop("teleop", TaskConfig::periodic(std::chrono::milliseconds(1), 0), config,
               saw::teleop::law_spec<saw::teleop::CollaborativeLaw>(config)) {
    manager.add(master);
    manager.add(slave);
    manager.add(delay);
    manager.add(teleop);
    manager.connect("master_delay", "source", "master", "arm");
    manager.connect("teleop", "master", "master_delay", "arm");
    manager.connect("teleop", "slave", "slave", "arm");
    manager.start_stepped();
  }
  // n periods; a master that does not publish is one that went silent.
  void step(int n = 1, bool publish_master = true) {
    for (int i = 0; i < n; ++i) publish_master ? stepper({&master, &slave}) : stepper({&slave});
  }
  FakeDevice master{"master"}, slave{"slave"};
  saw::teleop::DelayTask delay;
  saw::teleop::Teleoperation teleop;
  Manager manager;
  Stepper stepper{manager};
};

}  // namespace saw::testing
