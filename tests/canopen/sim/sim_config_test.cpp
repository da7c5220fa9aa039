// saw-can-sim's YAML file: what it sets, and every mistake named with file:line:column and key.
#include "saw/canopen/sim/sim_config.hpp"

#include <gtest/gtest.h>

#include <string>

#include "saw/deploy/config_error.hpp"

namespace saw::canopen::sim {
namespace {

TEST(SimConfigFile, SetsTheBusTheCycleTheDrivesAndTheFaults) {
  const SimConfig c = parse_sim_config(R"(
bus: virtual:lab
period: 500us
drives:
  - node: 3
    eds: vendor.eds
    heartbeat_ms: 100
    motor: {load_inertia: 0.2, viscous_friction: 1.0e-4, load_torque: 1.5}
  - node: 4
faults: ["4:over-current:1.5", "3:bus-off:3:0.5"]
)",
                                       "/etc/sim/lab.yaml");
  EXPECT_EQ(c.bus, "virtual:lab");
  EXPECT_EQ(c.period, 500'000);
  ASSERT_EQ(c.drives.size(), 2u);
  EXPECT_EQ(c.drives[0].node, 3);
  EXPECT_EQ(c.drives[0].eds, "/etc/sim/vendor.eds") << "relative to the file";
  EXPECT_EQ(c.drives[0].heartbeat_ms, std::uint16_t{100});
  EXPECT_DOUBLE_EQ(c.drives[0].motor.load_inertia, 0.2);
  EXPECT_DOUBLE_EQ(c.drives[0].motor.load_torque, 1.5);
  EXPECT_DOUBLE_EQ(c.drives[0].motor.motor_inertia, MotorParameters{}.motor_inertia);
  EXPECT_EQ(c.drives[1].eds, "") << "the built-in EDS";
  EXPECT_FALSE(c.drives[1].heartbeat_ms);
  ASSERT_EQ(c.faults.size(), 2u);
  EXPECT_EQ(c.faults[1].fault.kind, FaultKind::bus_off);
  EXPECT_NO_THROW(check(c));
}

void expect_error(const std::string& yaml, int line, const std::string& key, const std::string& what) {
  try {
    (void)parse_sim_config(yaml, "sim.yaml");
    ADD_FAILURE() << "accepted:\n" << yaml;
  } catch (const deploy::ConfigError& e) {
    EXPECT_EQ(e.file(), "sim.yaml");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(SimConfigFile, MistakesNameTheirPlace) {
  expect_error("drives:\n  - node: 1\n    motr: {}\n", 3, "drives[0].motr", "unknown parameter");
  expect_error("drives:\n  - node: 1\n  - node: 1\n", 3, "drives[1].node", "simulated twice");
  expect_error("drives:\n  - node: 200\n", 2, "drives[0].node", "out of range");
  expect_error("drives:\n  - node: 1\n    motor: {motor_inertia: 0}\n", 3, "drives[0].motor",
               "motor_inertia");
  expect_error("drives:\n  - node: 1\nfaults: [\"2:over-current:1\"]\n", 3, "faults[0]",
               "not one of the drives");
  expect_error("drives:\n  - node: 1\nfaults: [\"1:melt:1\"]\n", 3, "faults[0]", "unknown kind 'melt'");
  expect_error("period: 10us\ndrives:\n  - node: 1\n", 1, "period", "50us .. 100ms");
  expect_error("bus: virtual:x\n", 1, "drives", "non-empty list");
  expect_error("drives: [\n", 2, "", "YAML syntax");
}

TEST(SimConfigFile, CheckRefusesWhatTheCommandLineCanGetWrong) {
  SimConfig c;
  EXPECT_THROW(check(c), std::invalid_argument) << "no drive";
  c.drives.resize(2);
  c.drives[0].node = c.drives[1].node = 7;
  EXPECT_THROW(check(c), std::invalid_argument) << "twice";
  c.drives[1].node = 8;
  c.faults.push_back(parse_scheduled_fault("9:bus-off:1"));
  EXPECT_THROW(check(c), std::invalid_argument) << "a fault for no drive";
}

}  // namespace
}  // namespace saw::canopen::sim
