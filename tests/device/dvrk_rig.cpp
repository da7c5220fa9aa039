// The conformance suite on the dVRK arm device (drivers/dvrk) as an MTM, its hardware a scripted
// stand-in for the gateway's import that keeps and applies the last wrench as a dVRK does.
#include <gtest/gtest.h>

#include <cmath>

#include "../drivers/fake_dvrk_import.hpp"
#include "conformance.hpp"
#include "saw/detail/access.hpp"
#include "saw/drivers/dvrk/dvrk_arm.hpp"
#include "saw/manager.hpp"

namespace saw::conformance {
namespace {

using namespace saw::drivers::dvrk;

class DvrkRig : public Rig {
 public:
  DvrkRig() {
    import_.record = false;
    import_.state = {OperatingStateValue::enabled, true, false};  // powered and homed at its console
    make(true);
  }
  Device& device() override { return *device_; }
  void cycle(int n) override {
    for (int i = 0; i < n; ++i, now_ += period()) {
      if (publishing_) import_.publish(now_);
      detail::Access::step(*device_, now_);
    }
  }
  void send(Command c) override {
    Wrench w{};
    w.force[0] = value_of(c, 1.0, device_->contract().max_force);
    write("servo_cf", w);
  }
  // An arm in FAULT or disabled applies nothing; else its last wrench.
  double output() const override {
    if (import_.state.state != OperatingStateValue::enabled) return 0;
    const auto& f = import_.wrench.force;
    return std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  }
  bool safe() const override { return output() == 0; }
  // The dVRK stops publishing (its process hung) while its last wrench stays applied.
  bool break_hardware() override {
    publishing_ = false;
    return true;
  }
  // The deployment did not connect the device to an import: its start fails, saying so.
  bool fail_start() override {
    make(false);
    return true;
  }

 private:
  void make(bool connected) {
    DvrkArmConfig c;
    c.kind = ArmKind::mtm;
    device_ = std::make_unique<DvrkArm>("dvrk", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    if (connected) {
      manager_ = std::make_unique<Manager>();
      manager_->add(import_);
      manager_->add(*device_);
      manager_->connect("dvrk", "dvrk", "import", "dvrk");
      import_.state_table().finalize();
    }
    wire(*device_, {"servo_cf", "state_command"});
  }
  drivers::dvrk::testing::FakeImport import_{"import"};
  std::unique_ptr<Manager> manager_;
  std::unique_ptr<DvrkArm> device_;
  TimeNs now_ = 1'000'000'000;
  bool publishing_ = true;
};

INSTANTIATE_TEST_SUITE_P(DvrkArm, DeviceConformance,
                         ::testing::Values(Driver{"dvrk_mtm", [] { return std::make_unique<DvrkRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
