// The simulated drive's parts on their own: the motor model, fault specifications, the dictionary.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "saw/canopen/cia402.hpp"
#include "saw/canopen/sim/drive_dictionary.hpp"
#include "saw/canopen/sim/fault.hpp"
#include "saw/canopen/sim/motor_model.hpp"

namespace saw::canopen::sim {
namespace {

constexpr TimeNs ms = 1'000'000;

TEST(SimMotorModel, TorqueAcceleratesTheReflectedInertia) {
  MotorParameters p;
  p.viscous_friction = 0;
  MotorModel m(p);
  m.set_gear_ratio(100);
  EXPECT_DOUBLE_EQ(m.inertia(), 2.0e-5 + 0.05 / 1e4);
  ServoCommand c;
  c.loop = ServoCommand::Loop::torque;
  c.torque = 0.1;
  c.max_torque = 1;
  m.advance(c, 100 * ms);
  EXPECT_NEAR(m.velocity(), 0.1 / m.inertia() * 0.1, 1e-6);
  EXPECT_NEAR(m.position(), 0.5 * 0.1 / m.inertia() * 0.01, 20 * 1e-3) << "Euler's error at a 50 µs step";
  c.torque = 5;  // beyond the power stage
  const double v = m.velocity();
  m.advance(c, 10 * ms);
  EXPECT_NEAR(m.velocity() - v, 1.0 / m.inertia() * 0.01, 1e-6) << "clamped to max_torque";
}

TEST(SimMotorModel, ViscousFrictionAndALoadSlowTheMotor) {
  MotorParameters p;
  p.load_torque = 1.0;  // at the output: 0.01 N·m at the motor through 100:1
  MotorModel m(p);
  m.set_gear_ratio(100);
  m.advance(ServoCommand{}, 10 * ms);
  EXPECT_LT(m.velocity(), 0) << "an unpowered motor gives way to the load";
}

TEST(SimMotorModel, VelocityLoopSettlesAndHoldsAgainstALoad) {
  MotorParameters p;
  p.load_torque = 2.0;
  MotorModel m(p);
  m.set_gear_ratio(100);
  ServoCommand c;
  c.loop = ServoCommand::Loop::velocity;
  c.velocity = 50;
  c.max_torque = 0.95;
  double peak = 0;
  for (int i = 0; i < 200; ++i) {
    m.advance(c, 1 * ms);
    peak = std::max(peak, m.velocity());
  }
  EXPECT_NEAR(m.velocity(), 50, 0.05) << "the integral takes the load";
  EXPECT_LT(peak, 50 * 1.15) << "the PI's zero: a step overshoots by about a tenth";
}

TEST(SimMotorModel, PositionLoopReachesTheTarget) {
  MotorModel m(MotorParameters{});
  m.set_gear_ratio(100);
  ServoCommand c;
  c.loop = ServoCommand::Loop::position;
  c.position = 10;
  c.max_torque = 0.95;
  for (int i = 0; i < 500; ++i) m.advance(c, 1 * ms);
  EXPECT_NEAR(m.position(), 10, 1e-3);
  EXPECT_NEAR(m.velocity(), 0, 1e-2);
}

TEST(SimMotorModel, TheResultDoesNotDependOnTheCallersStep) {
  ServoCommand c;
  c.loop = ServoCommand::Loop::velocity;
  c.velocity = 30;
  c.max_torque = 0.5;
  MotorModel fine(MotorParameters{}), coarse(MotorParameters{});
  for (int i = 0; i < 400; ++i) fine.advance(c, 250'000);
  for (int i = 0; i < 100; ++i) coarse.advance(c, 1 * ms);
  EXPECT_DOUBLE_EQ(fine.position(), coarse.position());
}

TEST(SimMotorModel, ParametersAreChecked) {
  const auto refused = [](auto change, const char* name) {
    MotorParameters p;
    change(p);
    try {
      p.check();
      ADD_FAILURE() << name << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  refused([](MotorParameters& p) { p.motor_inertia = 0; }, "motor_inertia");
  refused([](MotorParameters& p) { p.load_inertia = -1; }, "load_inertia");
  refused([](MotorParameters& p) { p.viscous_friction = std::nan(""); }, "viscous_friction");
  refused([](MotorParameters& p) { p.position_bandwidth_hz = 100; }, "position_bandwidth_hz");
  refused([](MotorParameters& p) { p.integration_step = 2 * ms; }, "integration_step");
  refused([](MotorParameters& p) { p.velocity_bandwidth_hz = 5000; }, "integration_step");
  EXPECT_NO_THROW(MotorParameters{}.check());
}

TEST(SimFaultSpec, CommandLineFormsParse) {
  ScheduledFault s = parse_scheduled_fault("3:over-current:1.5");
  EXPECT_EQ(s.node, 3);
  EXPECT_EQ(s.fault.kind, FaultKind::over_current);
  EXPECT_EQ(s.at, 1'500'000'000);
  s = parse_scheduled_fault("1:bus-off:2:0.25");
  EXPECT_EQ(s.fault.kind, FaultKind::bus_off);
  EXPECT_EQ(s.fault.duration, 250 * ms);
  s = parse_scheduled_fault("127:sdo-abort=0x6064.0:0");
  EXPECT_EQ(s.fault.object, (ObjectAddress{0x6064, 0}));
  EXPECT_EQ(s.fault.abort, SdoAbort::hardware);
  s = parse_scheduled_fault("2:sdo-abort=0x1018.4/0x06020000:1:3");
  EXPECT_EQ(s.fault.object, (ObjectAddress{0x1018, 4}));
  EXPECT_EQ(s.fault.abort, SdoAbort::no_object);
  EXPECT_EQ(s.fault.duration, 3'000'000'000);
  EXPECT_EQ(describe(s), "node 2: sdo-abort 0x1018:04 (0x06020000) at 1.000 s for 3.000 s");
  EXPECT_EQ(describe(parse_scheduled_fault("4:heartbeat-loss:0.5")),
            "node 4: heartbeat-loss at 0.500 s until cleared");
  for (unsigned k = 1; k <= fault_kind_count; ++k) {
    const auto kind = static_cast<FaultKind>(k);
    EXPECT_EQ(fault_kind_from_string(to_string(kind)), kind);
    EXPECT_EQ(fault_kind_from_code(k), kind);
  }
}

TEST(SimFaultSpec, MistakesAreNamed) {
  const auto says = [](const char* text, const char* what) {
    try {
      (void)parse_scheduled_fault(text);
      ADD_FAILURE() << text << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  says("1:over-current", "expected <node>:<kind>");
  says("0:over-current:1", "node must be 1..127");
  says("128:over-current:1", "node must be 1..127");
  says("1:overcurrent:1", "unknown kind 'overcurrent'");
  says("1:over-current:-1", "the time must be");
  says("1:over-current:1:2", "is an event");
  says("1:sdo-abort:1", "needs its object");
  says("1:sdo-abort=6064:1", "<index>.<sub>");
  says("1:sdo-abort=0x6064.0/0:1", "non-zero");
  says("1:bus-off=1:1", "takes no argument");
}

TEST(SimDriveDictionary, TheBuiltInEdsIsTheShippedFile) {
  const Eds eds = load_drive_eds("");
  EXPECT_EQ(eds.file, builtin_eds_name);
  EXPECT_EQ(eds.device.rx_pdos, 4);
  EXPECT_EQ(eds.device.tx_pdos, 4);
  const Eds shipped = load_drive_eds(SAW_SIM_DRIVE_EDS);
  EXPECT_EQ(shipped.entries.size(), eds.entries.size());
  const auto mappings = eds_pdo_mappings(eds, 9);
  EXPECT_EQ(mappings.size(), 8u);
  const LocalDictionary d = make_drive_dictionary(eds, 9);
  std::uint32_t v = 0;
  EXPECT_EQ(d.get(ObjectAddress{0x1400, 1}, v), Codec::ok);
  EXPECT_EQ(v, 0x209u);
  EXPECT_EQ(d.get(ObjectAddress{0x1401, 1}, v), Codec::ok);
  EXPECT_EQ(v, 0x80000309u);
}

TEST(SimDriveDictionary, AnEdsThatTypesAnObjectOtherwiseIsRefusedWithItsLine) {
  // sim_drive.eds with the statusword made UNSIGNED32.
  std::string eds(builtin_eds());
  const std::size_t section = eds.find("[6041]");
  ASSERT_NE(section, std::string::npos);
  const std::size_t type = eds.find("DataType=0x0006", section);
  eds.replace(type, 15, "DataType=0x0007");
  const int line =
      1 + static_cast<int>(std::count(eds.begin(), eds.begin() + static_cast<long>(section), '\n'));
  try {
    (void)make_drive_dictionary(parse_eds(eds, "odd.eds"), 1);
    ADD_FAILURE() << "accepted";
  } catch (const deploy::ConfigError& e) {
    EXPECT_EQ(e.file(), "odd.eds");
    EXPECT_EQ(e.line(), line);
    EXPECT_EQ(e.key(), "0x6041:00");
    EXPECT_NE(std::string(e.what()).find("as UNSIGNED16, the file says UNSIGNED32"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace saw::canopen::sim
