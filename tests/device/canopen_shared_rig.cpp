// The conformance suite on the CANopen arm as a client of a shared bus task (canopen_bus), in
// cyclic synchronous torque, with in-process CiA 402 drives on an in-memory bus: each cycle the
// bus task (frames routed, the arm's RPDOs of the last cycle, SYNC), the arm, then the drives.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "../canopen/shared_rig.hpp"
#include "conformance.hpp"

namespace saw::conformance {
namespace {

using namespace saw::canopen;
using namespace saw::canopen::test;

class CanopenSharedRig : public Rig {
 public:
  CanopenSharedRig() {
    arm_ = bus_.make("arm", {1, 2, 3}, [](CanopenArmConfig& c) {
      c.mode = cia402::cst;
      c.contract.start_enabled = false;
      c.feedback_timeout = 0;  // the default: 10 periods
    });
    wire(*arm_, {"servo_jf", "state_command"});
  }
  Device& device() override { return *arm_; }
  void cycle(int n) override { bus_.cycle({arm_.get()}, n); }
  void send(Command c) override {
    const double v = value_of(c, 0.1, arm_->arm_config().joints[0].units.rated_torque * 1000);
    JointState js;
    js.size = 3;
    js.effort = {v, v, v};
    write("servo_jf", js);
  }
  double output() const override {
    int most = 0;
    // What the motors get: a drive applies its target torque only in operation enabled.
    for (const auto& d : bus_.drives.list)
      if (d->state() == cia402::State::operation_enabled)
        most = std::max(most, std::abs(int{d->target_torque()}));
    return most;
  }
  bool safe() const override {
    for (const auto& d : bus_.drives.list)
      if (d->state() == cia402::State::operation_enabled) return false;
    return true;
  }
  bool break_hardware() override {
    bus_.drives[1].raise_fault(0x2310);
    return true;
  }
  bool fail_start() override {
    for (auto& d : bus_.drives.list) d->set_silent(true);
    return true;
  }
  // The drives take the last frames the arm sent itself as it stopped (no bus task cycles then).
  void settle_after_stop() override {
    bus_.bus_port.now = bus_.now;
    bus_.drives.step(bus_.now);
  }
  // No SYNC, RPDO or master heartbeat from now on: the drives alone (their consumers watch the
  // bus task's heartbeat, 0x1016:01, and do what 0x6007 says).
  bool kill_controller(TimeNs alone) override {
    for (TimeNs t = 0; t < alone; t += ms, bus_.now += ms) {
      bus_.bus_port.now = bus_.now;
      bus_.drives.step(bus_.now);
    }
    return true;
  }

 private:
  SharedRig bus_;
  std::unique_ptr<CanopenArm> arm_;
};

INSTANTIATE_TEST_SUITE_P(CanopenArmOnABusTask, DeviceConformance,
                         testing::Values(Driver{"canopen_arm_on_a_bus_task",
                                                [] { return std::make_unique<CanopenSharedRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
