// The falcon's "arm" is the CRTK arm a sim_haptic_device provides: a client written for one
// connects to the other, and the grip buttons reach it as clutch and operator_present events.
#include <gtest/gtest.h>

#include "saw/crtk_arm.hpp"
#include "saw/drivers/falcon/falcon_device.hpp"
#include "saw/drivers/falcon/sim_firmware.hpp"
#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;
using namespace saw::drivers::falcon;

// What a teleoperation task requires of a master, as it would of a simulated device.
class Client : public saw::Task {
 public:
  Client() : Task("client", saw::TaskConfig::periodic(1ms, 0)) {
    namespace arm = saw::crtk::arm;
    auto& r = require("arm");
    saw::crtk::require(r, arm::measured_cp, measured_cp);
    saw::crtk::require(r, arm::measured_cv, measured_cv);
    saw::crtk::require(r, arm::measured_js, measured_js);
    saw::crtk::require(r, arm::operating_state, operating_state);
    saw::crtk::require(r, arm::servo_cf, servo_cf);
    saw::crtk::require(r, arm::state_command, state_command);
    saw::crtk::require(r, arm::clutch,
                       [this](const saw::ButtonEvent& b) { ++clutch_events, clutch = b.pressed; });
    saw::crtk::require(r, arm::operator_present,
                       [this](const saw::ButtonEvent& b) { ++operator_events, present = b.pressed; });
    saw::crtk::require(r, arm::operating_state_event, [this](const saw::OperatingState& s) { last = s; });
  }
  saw::FunctionRead<saw::Pose> measured_cp;
  saw::FunctionRead<saw::Twist> measured_cv;
  saw::FunctionRead<saw::JointState> measured_js;
  saw::FunctionRead<saw::OperatingState> operating_state;
  saw::FunctionWrite<saw::Wrench> servo_cf;
  saw::FunctionWrite<saw::StateCommand> state_command;
  int clutch_events = 0, operator_events = 0;
  bool clutch = false, present = false;
  saw::OperatingState last{};
};

TEST(FalconArmInterface, ASimDeviceClientConnectsAndSeesHomingAndButtons) {
  auto transport = std::make_unique<SimTransport>();
  SimFalconFirmware& sim = transport->firmware();
  FalconDevice device("falcon", saw::TaskConfig::periodic(1ms, 0), {}, std::move(transport));
  Client client;
  saw::Manager m;
  m.add(device);
  m.add(client);
  m.connect("client", "arm", "falcon", "arm");
  m.start_stepped();
  auto steps = [&](int n) { m.step_until(m.simulated_time() + saw::TimeNs{n} * 1'000'000); };
  for (int i = 0; i < 3000 && !client.last.is_homed; ++i) steps(1);
  EXPECT_TRUE(client.last.is_homed) << "the homing's end is an operating_state event";
  sim.set_buttons(status::button_center);
  steps(3);
  EXPECT_EQ(client.clutch_events, 1);
  EXPECT_TRUE(client.clutch);
  sim.set_buttons(status::button_center | status::button_forward);
  steps(3);
  EXPECT_EQ(client.operator_events, 1);
  EXPECT_TRUE(client.present);
  sim.set_buttons(0);
  steps(3);
  EXPECT_EQ(client.clutch_events, 2);
  EXPECT_FALSE(client.clutch);
  EXPECT_FALSE(client.present);
  saw::JointState js;
  ASSERT_EQ(client.measured_js(js), saw::Status::ok);
  EXPECT_EQ(js.size, 3u);
  EXPECT_EQ(js.name_of(0), "arm0");
  EXPECT_TRUE(saw::check_value(js));
  saw::OperatingState s;
  ASSERT_EQ(client.operating_state(s), saw::Status::ok);
  EXPECT_EQ(s.state, saw::OperatingStateValue::enabled);
  m.stop();
}

}  // namespace
