// A law's declared inputs: read commands of either device that the task requires, reads, checks
// and hands over by declaration alone (law_input.hpp) — the seam a lab's law grows through
// without a task edit (examples/lab_force_law).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "saw/crtk_arm.hpp"
#include "saw/eigen.hpp"
#include "saw/manager.hpp"
#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/stepper.hpp"

namespace {

using saw::teleop::Input;
using saw::teleop::LawCommand;
using saw::teleop::LawInputs;
using saw::teleop::LawSide;
using saw::teleop::Output;

// The master feels what the slave's sensor reads; nothing else.
struct SensorLaw {
  struct Settings {
    double unused = 0;
  };
  static constexpr std::string_view name = "sensor_test", description = "test";
  static constexpr auto declared_settings = std::tuple{};
  static constexpr auto declared_inputs = std::tuple{Input<saw::Wrench>{LawSide::slave, "measured_cf"}};
  SensorLaw(const Settings& s, const saw::teleop::LawContext&) : s_(s) {}
  Settings& settings() noexcept { return s_; }
  void reset(const LawInputs&) noexcept {}
  LawCommand step(const LawInputs& in) noexcept {
    LawCommand out;
    if (const auto* w = in.declared.get<saw::Wrench>(0)) out.master_force = saw::to_eigen(w->force);
    // Asked for as another type: nullptr, never a Wrench's bytes as a Pose (the slave would move).
    if (in.declared.get<saw::Pose>(0) != nullptr || in.declared.get<saw::Wrench>(1) != nullptr)
      out.slave_force = Eigen::Vector3d(9, 9, 9);
    return out;
  }
  Settings s_;
};

// A device with no force sensor: the arm's reads and servo_cf, no measured_cf.
class NoSensor : public saw::Component {
 public:
  NoSensor() : Component("slave") {
    namespace arm = saw::crtk::arm;
    auto& p = provide("arm");
    saw::crtk::provide(p, arm::measured_cp, state_table(), &pose_);
    saw::crtk::provide(p, arm::measured_cv, state_table(), &twist_);
    saw::crtk::provide(p, arm::servo_cf, [](const saw::Wrench&) {});
  }
  saw::Pose pose_;
  saw::Twist twist_;
};

saw::teleop::TeleopConfig config() {
  saw::teleop::TeleopConfig c;
  c.stale_timeout = 0.01;  // 10 ms
  return c;
}

struct Rig {
  Rig()
      : teleop("teleop", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0), config(),
               saw::teleop::law_spec<SensorLaw>()) {
    manager.add(master);
    manager.add(slave);
    manager.add(teleop);
    manager.connect("teleop", "master", "master", "arm");
    manager.connect("teleop", "slave", "slave", "arm");
    manager.start_stepped();
  }
  void step(int n = 1) {
    for (int i = 0; i < n; ++i) stepper({&master, &slave});
  }
  saw::testing::FakeDevice master{"master"}, slave{"slave"};
  saw::teleop::Teleoperation teleop;
  saw::Manager manager;
  saw::testing::Stepper stepper{manager};
};

TEST(DeclaredInputs, TheLawGetsTheSlavesWrenchCheckedAndTheLastValidOne) {
  Rig r;
  r.slave.wrench.force = {1, -2, 0.5};
  r.step(3);
  EXPECT_EQ(r.master.force, (saw::Vec3{1, -2, 0.5})) << "the slave's measured_cf reached the law";
  EXPECT_EQ(r.slave.force, (saw::Vec3{0, 0, 0})) << "as a Wrench only, and only as input 0";
  r.slave.wrench.force = {std::nan(""), 0, 0};  // not a valid Wrench: never handed over
  r.step(3);
  EXPECT_EQ(r.master.force, (saw::Vec3{1, -2, 0.5})) << "the last valid one stands";
  EXPECT_EQ(r.teleop.operating_state(), saw::OperatingStateValue::enabled) << "for less than stale_timeout";
}

TEST(DeclaredInputs, ADeclaredInputWithoutValidValuesForStaleTimeoutFaultsTheTaskNamingIt) {
  Rig r;
  r.slave.wrench.force = {1, 0, 0};
  r.step(3);
  r.slave.wrench.force = {std::nan(""), 0, 0};
  r.step(20);
  EXPECT_EQ(r.teleop.operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(r.teleop.fault().code, saw::FaultCode::input_stale);
  EXPECT_NE(std::string(r.teleop.fault_reason()).find("measured_cf"), std::string::npos)
      << r.teleop.fault_reason();
  EXPECT_EQ(r.master.force, (saw::Vec3{0, 0, 0})) << "zero force, as for any stale input";
}

TEST(DeclaredInputs, ARequiredInputTheDeviceDoesNotHaveIsAFailedStartNamingIt) {
  saw::testing::FakeDevice master{"master"};
  NoSensor slave;
  saw::teleop::Teleoperation teleop("teleop", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0),
                                    config(), saw::teleop::law_spec<SensorLaw>());
  saw::Manager manager;
  manager.add(master);
  manager.add(slave);
  manager.add(teleop);
  manager.connect("teleop", "master", "master", "arm");
  try {
    manager.connect("teleop", "slave", "slave", "arm");
    manager.start_stepped();
    ADD_FAILURE() << "started without the law's input";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("measured_cf"), std::string::npos) << e.what();
  }
}

// Sends a declared value to the slave every cycle it steps (as a passive law its port's energy),
// and shows in the master's force whether its declared input came with a new row.
struct SendingLaw {
  struct Settings {
    double unused = 0;
  };
  static constexpr std::string_view name = "sending_test", description = "test";
  static constexpr auto declared_settings = std::tuple{};
  static constexpr auto declared_inputs = std::tuple{Input<saw::Wrench>{LawSide::master, "measured_cf"}};
  static constexpr auto declared_outputs = std::tuple{Output<double>{LawSide::slave, "remote_value"}};
  SendingLaw(const Settings& s, const saw::teleop::LawContext&) : s_(s) {}
  Settings& settings() noexcept { return s_; }
  void reset(const LawInputs&) noexcept {}
  LawCommand step(const LawInputs& in) noexcept {
    LawCommand out;
    out.slave_force = Eigen::Vector3d(1, 0, 0);
    out.master_force.x() = in.declared.fresh(0) ? 1 : 0;
    (void)in.outputs.set(0, ++sent);
    return out;
  }
  Settings s_;
  double sent = 0;
};

// A slave that logs, in order, each force ('f') and each declared value ('v') it is sent.
class Receiver : public saw::testing::FakeDevice {
 public:
  Receiver() : FakeDevice("slave") {
    provided("arm")->add_command_write<double>("remote_value", [this](const double& v) {
      flush();
      log += 'v';
      last = v;
    });
  }
  // The forces counted since the last flush, logged: a force and a value of one cycle are in the
  // order they came.
  void flush() {
    for (; logged < commands; ++logged) log += 'f';
  }
  std::string log;
  int logged = 0;
  double last = 0;
};

TEST(DeclaredOutputs, AValueTheLawSetsIsSentBeforeTheForceAndNothingWhileItHolds) {
  saw::testing::FakeDevice master{"master"};
  Receiver slave;
  saw::teleop::Teleoperation teleop("teleop", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0),
                                    config(), saw::teleop::law_spec<SendingLaw>());
  saw::Manager manager;
  manager.add(master);
  manager.add(slave);
  manager.add(teleop);
  manager.connect("teleop", "master", "master", "arm");
  manager.connect("teleop", "slave", "slave", "arm");
  manager.start_stepped();
  saw::testing::Stepper stepper{manager};
  const auto step = [&](std::initializer_list<saw::testing::FakeDevice*> publish) {
    stepper(publish);
    slave.flush();
  };
  for (int i = 0; i < 5; ++i) {
    step({&master, &slave});
    if (i >= 2) {
      EXPECT_EQ(slave.log.substr(slave.log.size() - 2), "vf") << "the value before the force: " << slave.log;
    }
  }
  ASSERT_EQ(teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_GT(slave.last, 0);
  // Fresh only with a new row of its side: the master not publishing for 3 cycles (less than
  // stale_timeout) gives the law its input, not fresh.
  EXPECT_EQ(master.force[0], 1) << "a new master row each cycle: fresh";
  step({&slave});
  EXPECT_EQ(master.force[0], 0) << "no new master row: not fresh";
  step({&master, &slave});
  EXPECT_EQ(master.force[0], 1);
  // Clutched, the law holds: forces (zero) still go to the slave, values do not.
  master.press_clutch(true);
  step({&master, &slave});
  step({&master, &slave});
  const std::string held_from = slave.log;
  for (int i = 0; i < 5; ++i) step({&master, &slave});
  EXPECT_EQ(slave.log.substr(held_from.size()), "fffff") << slave.log;
  master.press_clutch(false);
  for (int i = 0; i < 3; ++i) step({&master, &slave});
  EXPECT_NE(slave.log.rfind("vf"), std::string::npos);
  EXPECT_EQ(slave.log.back(), 'f');
  EXPECT_EQ(slave.log[slave.log.size() - 2], 'v') << "sending again once engaged: " << slave.log;
}

}  // namespace
