// The `falcon` type in deployments: its parameters' errors, the USB transport's open error, and
// config/teleop-falcon-sim.yaml teleoperating on the stepped clock.
#include "saw/deploy/deployment.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "saw/drivers/falcon/falcon_device.hpp"
#include "saw/drivers/falcon/registration.hpp"
#include "saw/drivers/sim_registration.hpp"
#include "saw/teleop/collaborative_control_force.hpp"
#include "saw/teleop/registration.hpp"

namespace {

saw::deploy::ComponentRegistry& registry() {
  static saw::deploy::ComponentRegistry r = [] {
    saw::deploy::ComponentRegistry x;
    saw::drivers::falcon::register_components(x);
    saw::drivers::sim::register_components(x);
    saw::teleop::register_components(x);
    return x;
  }();
  return r;
}

std::string falcon_file(const std::string& params) {
  return "deployment: {name: t, clock: stepped}\ncomponents:\n  - name: m\n    type: falcon\n"
         "    task: {period: 1ms}\n    params: " +
         params + "\n";
}

std::string error_of(const std::string& params) {
  try {
    auto d = saw::deploy::make_deployment(falcon_file(params), "falcon.yaml", registry());
    d.start();
    d.stop();
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

TEST(FalconDeployment, ParameterErrorsNameFileLineAndKey) {
  const std::string e1 = error_of("{transport: bluetooth}");
  EXPECT_NE(e1.find("falcon.yaml:6"), std::string::npos) << e1;
  EXPECT_NE(e1.find("transport"), std::string::npos) << e1;
  const std::string e2 = error_of("{transport: usb}");
  EXPECT_NE(e2.find("firmware"), std::string::npos) << e2;
  const std::string e3 = error_of("{transport: sim, max_force: 80}");
  EXPECT_NE(e3.find("max_force"), std::string::npos) << e3;
  const std::string e4 = error_of("{transport: sim, clutch_buttons: 16}");
  EXPECT_NE(e4.find("clutch_buttons"), std::string::npos) << e4;
  const std::string e5 = error_of("{transport: sim, typo: 1}");
  EXPECT_NE(e5.find("typo"), std::string::npos) << e5;
}

// No Falcon here: starting a USB Falcon says so (or that there is no USB at all).
TEST(FalconDeployment, AUsbFalconWithoutTheDeviceFailsToStartSayingWhy) {
  const std::string e = error_of("{transport: usb, firmware: " SAW_FALCON_TEST_FIRMWARE "}");
  std::printf("start: %s\n", e.c_str());
  EXPECT_TRUE(e.find("no Falcon found on the USB buses searched") != std::string::npos ||
              e.find("libusb_init failed") != std::string::npos)
      << e;
}

TEST(FalconDeployment, ShippedFalconSimTeleoperatesInSteppedMode) {
  auto d = saw::deploy::load_deployment(SAW_SOURCE_DIR "/config/teleop-falcon-sim.yaml", registry());
  d.set_clock(saw::deploy::Clock::stepped);
  d.start();
  d.run_for(10.0);
  d.stop();
  const auto* master = d.find<saw::drivers::falcon::FalconDevice>("master");
  const auto* t = d.find<saw::teleop::CollaborativeControlForce>("teleop");
  ASSERT_NE(master, nullptr);
  ASSERT_NE(t, nullptr);
  EXPECT_TRUE(master->operating_state().is_homed);
  EXPECT_EQ(master->operating_state().state, saw::OperatingStateValue::enabled);
  EXPECT_EQ(master->summary().faults, 0u);
  EXPECT_EQ(t->operating_state(), saw::OperatingStateValue::enabled);
  std::printf("falcon-sim teleop: tracking RMS %.3f mm over %llu cycles\n", t->tracking_rms() * 1e3,
              static_cast<unsigned long long>(t->enabled_cycles()));
  EXPECT_LT(t->tracking_rms(), 2e-3);
  EXPECT_GT(t->tracking_rms(), 0.0) << "the master does move";
}

}  // namespace
