// The conformance suite on the CANopen arm (drivers/canopen) in cyclic synchronous torque, with
// in-process CiA 402 drives on an in-memory bus: what the motors get is each drive's target
// torque and state, as the drives decoded them from the bus.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "../canopen/arm_rig.hpp"
#include "conformance.hpp"

namespace saw::conformance {
namespace {

using namespace saw::canopen;
using namespace saw::canopen::test;

class CanopenRig : public Rig {
 public:
  CanopenRig() : config_(arm_config(cia402::cst)), port_(network_.attach("arm bus")) {
    config_.contract.start_enabled = false;
    for (const JointConfig& j : config_.joints) {
      TestDriveConfig d;
      d.node = j.node;
      drives_.list.push_back(std::make_unique<TestDrive>(network_, d));
    }
    config_.startup_pause = [this] {
      drives_.step(now_);
      now_ += ms;
      port_.now = now_;
      return now_;
    };
    arm_ = std::make_unique<CanopenArm>("arm", TaskConfig::periodic(std::chrono::milliseconds(1), 0), config_,
                                        port_);
    wire(*arm_, {"servo_jf", "state_command"});
  }
  Device& device() override { return *arm_; }
  void cycle(int n) override {
    for (int i = 0; i < n; ++i) {
      port_.now = now_;
      detail::Access::step(*arm_, now_);
      drives_.step(now_);
      now_ += ms;
    }
  }
  void send(Command c) override {
    const double v = value_of(c, 0.1, config_.joints[0].units.rated_torque * 1000);
    JointState js;
    js.size = 3;
    js.effort = {v, v, v};
    write("servo_jf", js);
  }
  double output() const override {
    int most = 0;
    // What the motors get: a drive applies its target torque only in operation enabled.
    for (const auto& d : drives_.list)
      if (d->state() == cia402::State::operation_enabled)
        most = std::max(most, std::abs(int{d->target_torque()}));
    return most;
  }
  // Drives: the power stage is off (or quick-stopping), not merely at zero torque.
  bool safe() const override {
    for (const auto& d : drives_.list)
      if (d->state() == cia402::State::operation_enabled) return false;
    return true;
  }
  // A drive reports an overcurrent (statusword fault, EMCY 0x2310).
  bool break_hardware() override {
    drives_[1].raise_fault(0x2310);
    return true;
  }
  // The drives do not answer the start-up's SDOs.
  bool fail_start() override {
    for (auto& d : drives_.list) d->set_silent(true);
    return true;
  }
  // The drives take the last frames the arm sent as it stopped.
  void settle_after_stop() override {
    port_.now = now_;
    drives_.step(now_);
  }
  // No SYNC, RPDO or master heartbeat from now on: the drives alone (their consumers watch the
  // arm's heartbeat, 0x1016:01, and do what 0x6007 says).
  bool kill_controller(TimeNs alone) override {
    for (TimeNs t = 0; t < alone; t += ms, now_ += ms) {
      port_.now = now_;
      drives_.step(now_);
    }
    return true;
  }

 private:
  CanopenArmConfig config_;
  RingNetwork network_;
  RingPort& port_;
  Drives drives_{network_, {}};
  std::unique_ptr<CanopenArm> arm_;
  TimeNs now_ = 0;
};

INSTANTIATE_TEST_SUITE_P(CanopenArm, DeviceConformance,
                         testing::Values(Driver{"canopen_arm",
                                                [] { return std::make_unique<CanopenRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
