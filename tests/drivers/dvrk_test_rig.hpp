// Rig: a DvrkArm connected to a FakeImport on the stepped clock, for the dVRK device's tests.
#pragma once

#include <gtest/gtest.h>

#include <chrono>

#include "fake_dvrk_import.hpp"
#include "saw/drivers/dvrk/dvrk_arm.hpp"
#include "saw/manager.hpp"

namespace saw::drivers::dvrk::testing {

struct Rig {
  explicit Rig(DvrkArmConfig c) : arm("arm", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c) {
    manager.add(import);
    manager.add(arm);
    manager.connect("arm", "dvrk", "import", "dvrk");
    manager.start_stepped();
  }
  ~Rig() { manager.stop(); }
  // n periods; the import publishing unless the dVRK went silent.
  void step(int n = 1, bool publish = true) {
    for (int i = 0; i < n; ++i) {
      if (publish) import.publish(t);
      manager.step_until(t);
      t += 1'000'000;
    }
  }
  void state_command(StateCommand c) { arm.provided("arm")->find_command("state_command")->execute(&c); }
  void servo_cf(Vec3 f) {
    Wrench w;
    w.force = f;
    arm.provided("arm")->find_command("servo_cf")->execute(&w);
  }
  void servo_cp(const Pose& p) { arm.provided("arm")->find_command("servo_cp")->execute(&p); }
  // Any command of the device's "arm" by name (move_cp, move_jp, free, servo_jp).
  template <class T>
  void command(const char* name, const T& value) {
    arm.provided("arm")->find_command(name)->execute(&value);
  }
  void command(const char* name) { arm.provided("arm")->find_command(name)->execute(nullptr); }
  OperatingStateValue state() const { return arm.operating_state().state; }

  FakeImport import{"import"};
  DvrkArm arm;
  Manager manager;
  TimeNs t = 0;
};

inline DvrkArmConfig mtm(bool home = true) {
  DvrkArmConfig c;
  c.kind = ArmKind::mtm;
  c.home = home;
  return c;
}

inline DvrkArmConfig psm(SafeCommand safe = SafeCommand::hold) {
  DvrkArmConfig c;
  c.kind = ArmKind::psm;
  c.safe_command = safe;
  c.home = true;
  return c;
}

// Enables and waits until following (the import powers and homes the arm), a wrench offered
// each cycle all along.
inline void enable_mtm(Rig& r) {
  r.state_command(StateCommand::enable);
  for (int i = 0; i < 100 && !r.arm.following(); ++i) {
    r.servo_cf({0.5, 0, 0});
    r.step();
  }
  ASSERT_TRUE(r.arm.following()) << "state " << static_cast<int>(r.state());
}

}  // namespace saw::drivers::dvrk::testing
