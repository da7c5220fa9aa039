// The `falcon` type in deployments: its parameters' errors, the USB transport's open error, and
// config/teleop-falcon-sim.yaml teleoperating on the stepped clock.
#include "saw/deploy/deployment.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#include "saw/drivers/falcon/falcon_device.hpp"
#include "saw/drivers/falcon/registration.hpp"
#include "saw/drivers/sim_registration.hpp"
#include "saw/teleop/registration.hpp"
#include "saw/teleop/teleoperation.hpp"

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
  // The device base's key, in its range up to the most the Falcon takes.
  const std::string e3 = error_of("{transport: sim, max_force: 25}");
  EXPECT_NE(e3.find("max_force"), std::string::npos) << e3;
  EXPECT_NE(e3.find("(0, 20] N"), std::string::npos) << e3;
  const std::string e7 = error_of("{transport: sim, homing_timeout: 5s}");
  EXPECT_NE(e7.find("falcon.yaml:6"), std::string::npos) << e7;
  EXPECT_NE(e7.find("is now home_timeout"), std::string::npos) << e7;
  const std::string e4 = error_of("{transport: sim, clutch_buttons: 16}");
  EXPECT_NE(e4.find("clutch_buttons"), std::string::npos) << e4;
  const std::string e5 = error_of("{transport: sim, typo: 1}");
  EXPECT_NE(e5.find("typo"), std::string::npos) << e5;
  // Reopening an unplugged Falcon waits on USB: only the I/O thread may (never the cycle).
  const std::string e6 = error_of("{transport: sim, reconnect: 1s}");
  EXPECT_NE(e6.find("falcon.yaml:6"), std::string::npos) << e6;
  EXPECT_NE(e6.find("reconnect"), std::string::npos) << e6;
  EXPECT_NE(e6.find("io_thread"), std::string::npos) << e6;
  EXPECT_EQ(error_of("{transport: sim, io_thread: true, reconnect: 1s}"), "");
}

// No Falcon here: starting a USB Falcon says so (or that there is no USB at all).
TEST(FalconDeployment, AUsbFalconWithoutTheDeviceFailsToStartSayingWhy) {
  const std::string e = error_of("{transport: usb, firmware: " SAW_FALCON_TEST_FIRMWARE "}");
  std::printf("start: %s\n", e.c_str());
  EXPECT_TRUE(e.find("no Falcon found on the USB buses searched") != std::string::npos ||
              e.find("libusb_init failed") != std::string::npos)
      << e;
}

struct Tracking {
  double rms = 0, max = 0;
  unsigned long long cycles = 0;
};

// Runs a shipped deployment 10 s on the stepped clock (deterministic: no machine-speed figure).
template <class Check>
Tracking run_shipped(const char* file, Check&& check) {
  auto d = saw::deploy::load_deployment(std::string(SAW_SOURCE_DIR "/config/") + file, registry());
  d.set_clock(saw::deploy::Clock::stepped);
  d.start();
  d.run_for(10.0);
  d.stop();
  const auto* t = d.find<saw::teleop::Teleoperation>("teleop");
  if (t == nullptr) throw std::runtime_error(std::string(file) + ": no teleop");
  EXPECT_EQ(t->operating_state(), saw::OperatingStateValue::enabled) << file;
  check(d);
  return {t->tracking_rms(), t->tracking_max(), static_cast<unsigned long long>(t->enabled_cycles())};
}

// The Falcon master tracks as the simulated Omni master does (same slave, law, gains and hand).
// The teleoperation holds while the Falcon homes (busy; its counts are relative until then), so
// the Falcon's figure is over the enabled cycles after homing; the Omni's over all of them.
// Teleoperating through the homing instead drags the slave elsewhere: 1.7 mm RMS, 29 mm max.
TEST(FalconDeployment, ShippedFalconSimTracksAsTheSimulatedOmniDoes) {
  const Tracking omni = run_shipped("teleop-sim.yaml", [](saw::deploy::Deployment&) {});
  const Tracking falcon = run_shipped("teleop-falcon-sim.yaml", [](saw::deploy::Deployment& d) {
    const auto* master = d.find<saw::drivers::falcon::FalconDevice>("master");
    ASSERT_NE(master, nullptr);
    EXPECT_TRUE(master->operating_state().is_homed);
    EXPECT_FALSE(master->operating_state().is_busy);
    EXPECT_EQ(master->operating_state().state, saw::OperatingStateValue::enabled);
    EXPECT_EQ(master->device_status().faults, 0u);
    EXPECT_EQ(master->summary().saturated, 0u);
  });
  std::printf("omni-sim teleop:   tracking RMS %.3f mm, max %.3f mm over %llu cycles\n", omni.rms * 1e3,
              omni.max * 1e3, omni.cycles);
  std::printf("falcon-sim teleop: tracking RMS %.3f mm, max %.3f mm over %llu cycles (after homing)\n",
              falcon.rms * 1e3, falcon.max * 1e3, falcon.cycles);
  EXPECT_GT(falcon.rms, 0.1e-3) << "the master does move";
  EXPECT_LT(falcon.rms, 1.5 * omni.rms);
  EXPECT_LT(falcon.rms, 0.7e-3);
  // The hand takes the grip after homing and brings it 35 mm back to where it was at power-up:
  // the slave follows that pull a few mm behind, never the homing itself.
  EXPECT_LT(falcon.max, 8e-3);
  EXPECT_LT(falcon.cycles, omni.cycles) << "homing is not counted";
  EXPECT_GT(falcon.cycles, omni.cycles - 500) << "homing takes about 0.1 s";
}

}  // namespace
