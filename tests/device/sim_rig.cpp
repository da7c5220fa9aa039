// The conformance suite on the simulated haptic device (drivers/sim): the simulator is the
// device's own dynamics, so what it applies is read from there.
#include <gtest/gtest.h>

#include <cmath>

#include "conformance.hpp"
#include "saw/drivers/sim_haptic_device.hpp"

namespace saw::conformance {
namespace {

class SimRig : public Rig {
 public:
  SimRig() {
    drivers::SimDeviceConfig c;
    c.start_enabled = false;
    device_ = std::make_unique<drivers::SimHapticDevice>(
        "sim", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    wire(*device_, {"servo_cf", "state_command"});
  }
  Device& device() override { return *device_; }
  void cycle(int n) override {
    for (int i = 0; i < n; ++i, now_ += period()) detail::Access::step(*device_, now_);
  }
  void send(Command c) override {
    const double v = c == Command::good         ? 1.0
                     : c == Command::not_finite ? NAN
                     : c == Command::infinite   ? INFINITY
                                                : 2 * device_->device_config().max_force;
    write("servo_cf", Wrench{{v, 0, 0}, {0, 0, 0}});
  }
  double output() const override { return device_->applied_force().norm(); }
  bool safe() const override { return device_->applied_force().isZero(); }
  bool break_hardware() override { return false; }

 private:
  std::unique_ptr<drivers::SimHapticDevice> device_;
  TimeNs now_ = 1'000'000'000;
};

INSTANTIATE_TEST_SUITE_P(SimHapticDevice, DeviceConformance,
                         testing::Values(Driver{"sim_haptic_device",
                                                [] { return std::make_unique<SimRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
