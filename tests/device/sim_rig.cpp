// The conformance suite on the simulated haptic device (drivers/sim): the simulator is the
// device's own dynamics, so what it applies is read from there.
#include <gtest/gtest.h>

#include <cmath>

#include "conformance.hpp"
#include "saw/drivers/sim_haptic_device.hpp"

namespace saw::conformance {
namespace {

class SimRig : public HapticRig {
 public:
  SimRig() : HapticRig(0) {
    drivers::SimDeviceConfig c;
    c.contract.start_enabled = false;
    device_ = std::make_unique<drivers::SimHapticDevice>(
        "sim", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    wire(*device_, {"servo_cf", "state_command"});
  }
  Device& device() override { return *device_; }
  double output() const override { return device_->applied_force().norm(); }
  bool safe() const override { return device_->applied_force().isZero(); }
  bool break_hardware() override { return false; }

 private:
  std::unique_ptr<drivers::SimHapticDevice> device_;
};

INSTANTIATE_TEST_SUITE_P(SimHapticDevice, DeviceConformance,
                         testing::Values(Driver{"sim_haptic_device",
                                                [] { return std::make_unique<SimRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
