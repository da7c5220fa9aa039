// A CanopenArm in this process drives CiA 402 drives simulated by another process (saw-can-sim)
// on a virtual CAN bus: start-up over SDO and NMT, enable, a CSP trajectory followed, a fault
// injected through the bus by the arm's own runtime SDO, and recovery by `enable`. Everything
// between the two is real: the shared-memory bus, the protocol, two processes' clocks.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "saw/can/bus.hpp"
#include "saw/can/virtual_bus.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/manager.hpp"
#include "saw/testing/child_process.hpp"
#include "saw/testing/unique_name.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using namespace std::chrono_literals;
using saw::testing::wait_for;
namespace co = saw::canopen;

// What a lab's client of the arm does: CRTK joint commands and state, and an SDO now and then.
class Client : public saw::Component {
 public:
  Client() : Component("client") {
    auto& arm = require("arm");
    arm.add_function("servo_jp", servo_jp);
    arm.add_function("state_command", state_command);
    arm.add_function("measured_js", measured_js);
    arm.add_function("operating_state", operating_state);
    require("canopen").add_function("sdo", sdo);
  }
  saw::OperatingStateValue state() {
    saw::OperatingState s;
    return operating_state(s) == saw::Status::ok ? s.state : saw::OperatingStateValue::disabled;
  }
  double position(std::size_t joint) {
    saw::JointState js;
    return measured_js(js) == saw::Status::ok ? js.position[joint] : NAN;
  }
  saw::FunctionWrite<saw::JointState> servo_jp;
  saw::FunctionWrite<saw::StateCommand> state_command;
  saw::FunctionRead<saw::JointState> measured_js;
  saw::FunctionRead<saw::OperatingState> operating_state;
  saw::FunctionQualifiedRead<co::SdoRequest, co::SdoReply> sdo;
};

co::CanopenArmConfig two_joints(const std::string& bus) {
  co::CanopenArmConfig c;
  c.bus = bus;
  c.mode = co::cia402::csp;
  for (const std::uint8_t node : {std::uint8_t{1}, std::uint8_t{2}}) {
    co::JointConfig j;
    j.name = "joint" + std::to_string(node);
    j.node = node;
    j.units = co::DriveUnits::rotary(4096, 100, 0.318);  // saw-can-sim's built-in EDS
    j.min = -2;
    j.max = 2;
    j.max_velocity = 2;
    j.following_error = 0.2;
    c.joints.push_back(j);
  }
  c.heartbeat_period = 50'000'000;
  c.heartbeat_timeout = 150'000'000;
  c.contract.command_timeout = 200'000'000;  // the test thread is no RT thread
  c.feedback_timeout = 200'000'000;          // a stall of the shared CI machine is not what this tests
  c.rpdo_deadline = 200'000'000;             // nor here: saw-can-sim's drives watch the RPDOs
  return c;
}

// Waits until every node has sent its boot-up message: the simulated drives are on the bus.
bool drives_booted(const std::string& bus, std::initializer_list<int> nodes) {
  saw::can::BusConfig config;
  config.uri = bus;
  auto b = saw::can::open_bus(config);
  unsigned seen = 0;
  return wait_for([&] {
    saw::can::Received r[64];
    const auto n = b->receive(r);
    for (std::size_t i = 0; i < n; ++i)
      for (int node : nodes)
        if (r[i].frame.can_id() == 0x700u + node && r[i].frame.len == 1 && r[i].frame.data[0] == 0)
          seen |= 1u << node;
    unsigned all = 0;
    for (int node : nodes) all |= 1u << node;
    return seen == all;
  });
}

TEST(CanopenProcesses, AnArmFollowsFaultsAndRecoversWithDrivesInAnotherProcess) {
  const std::string bus = "virtual:" + saw::testing::unique_name("arm");
  saw::testing::ChildProcess sim({SAW_CAN_SIM, "--bus", bus, "--node", "1", "--node", "2", "--load-inertia",
                                  "0.002", "--duration", "120"});
  ASSERT_GT(sim.pid(), 0);
  ASSERT_TRUE(drives_booted(bus, {1, 2})) << "saw-can-sim's drives never booted on " << bus;

  co::CanopenArm arm("arm", saw::TaskConfig::periodic(1ms, 0), two_joints(bus));
  Client client;
  saw::Manager m;
  m.add(arm);
  m.add(client);
  m.connect("client", "arm", "arm", "arm");
  m.connect("client", "canopen", "arm", "canopen");
  m.start();  // the start-up: NMT reset, boot-ups, PDO maps and 0x1017 by SDO, NMT start

  ASSERT_EQ(client.state_command(saw::StateCommand::enable), saw::Status::ok);
  ASSERT_TRUE(wait_for([&] { return client.state() == saw::OperatingStateValue::enabled; }))
      << "not enabled: " << saw::to_string(arm.fault());

  // A ramp of joint 1 to 0.4 rad at 0.5 rad/s, then a hold: the drive follows it.
  const double start = client.position(0);
  ASSERT_TRUE(std::isfinite(start));
  saw::JointState js;
  js.size = 2;
  const auto t0 = std::chrono::steady_clock::now();
  for (double t = 0; t < 1.0;
       t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()) {
    js.position = {start + 0.4 * std::min(t / 0.8, 1.0), 0};
    ASSERT_EQ(client.servo_jp(js), saw::Status::ok);
    std::this_thread::sleep_for(2ms);
  }
  js.position = {start + 0.4, 0};
  EXPECT_TRUE(wait_for([&] {
    (void)client.servo_jp(js);
    return std::abs(client.position(0) - (start + 0.4)) < 0.01;
  })) << "joint 1 at "
      << client.position(0) << " rad, asked " << start + 0.4;
  EXPECT_EQ(client.state(), saw::OperatingStateValue::enabled) << saw::to_string(arm.fault());

  // An over-current on drive 2, asked through the arm's own runtime SDO (saw-can-sim's 0x2F00.1).
  co::SdoRequest rq;
  rq.node = 2;
  rq.index = 0x2F00;
  rq.subindex = 1;
  rq.write = true;
  rq.size = 1;
  rq.data[0] = 1;
  co::SdoReply reply;
  ASSERT_EQ(client.sdo(rq, reply), saw::Status::ok);
  ASSERT_EQ(reply.status, saw::Status::ok);
  ASSERT_EQ(reply.abort, 0u) << co::sdo_abort_name(reply.abort);
  ASSERT_TRUE(wait_for([&] { return client.state() == saw::OperatingStateValue::fault; }));
  EXPECT_EQ(arm.fault().detail, 0x2310u) << saw::to_string(arm.fault());
  EXPECT_EQ(arm.fault().code, saw::FaultCode::device_error) << saw::to_string(arm.fault());

  // `enable` resets the drives' faults (the over-current was momentary) and walks them back.
  ASSERT_EQ(client.state_command(saw::StateCommand::enable), saw::Status::ok);
  EXPECT_TRUE(wait_for([&] { return client.state() == saw::OperatingStateValue::enabled; }))
      << saw::to_string(arm.fault());
  m.stop();
  saw::can::remove_virtual_bus(bus.substr(bus.find(':') + 1));  // a bus outlives its users, as vcan does
}

}  // namespace
