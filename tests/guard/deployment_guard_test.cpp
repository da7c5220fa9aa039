// The simulated teleoperation deployment (two KDL devices, a scripted hand, delay, teleop)
// does none of what the guard counts from its first cycle, on the stepped clock and on threads.
#include <gtest/gtest.h>

#include <thread>

#include "guard_support.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/drivers/sim_instrument.hpp"
#include "saw/manager.hpp"
#include "saw/rt_context.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/laws/passive_bilateral.hpp"
#include "saw/teleop/laws/surgical.hpp"
#include "saw/teleop/laws/wave_variables.hpp"
#include "saw/teleop/passivity_port.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/fake_wave_port.hpp"
#include "saw/testing/stepper.hpp"
#include "saw/testing/teleop_rig.hpp"

namespace {

using namespace std::chrono_literals;

struct Deployment {
  Deployment()
      : master("master", saw::TaskConfig::periodic(1ms, 0), master_config()),
        slave("slave", saw::TaskConfig::periodic(1ms, 0), saw::drivers::SimDeviceConfig{}),
        delay("master_delay", saw::TaskConfig::periodic(1ms, 0), link_config()),
        teleop("teleop", saw::TaskConfig::periodic(1ms, 0), teleop_config(),
               saw::teleop::law_spec<saw::teleop::CollaborativeLaw>(teleop_config())) {
    for (saw::Component* c : std::initializer_list<saw::Component*>{&master, &slave, &delay, &teleop})
      m.add(*c);
    m.connect("master_delay", "source", "master", "arm");
    m.connect("teleop", "master", "master_delay", "arm");
    m.connect("teleop", "slave", "slave", "arm");
  }
  // Both directions delayed, jittered and lossy: every path of the link runs under the guard.
  static saw::teleop::DelayConfig link_config() {
    saw::teleop::DelayConfig c;
    c.measured = {10'000'000, 2'000'000, 0.05, 1};
    c.commands = {10'000'000, 2'000'000, 0.05, 2};
    return c;
  }
  static saw::drivers::SimDeviceConfig master_config() {
    saw::drivers::SimDeviceConfig c;
    c.hand.kind = saw::drivers::HandScript::Kind::sinusoid;
    c.hand.amplitude = {0.03, 0.01, 0};
    return c;
  }
  static saw::testing::CollaborativeTeleopConfig teleop_config() {
    saw::testing::CollaborativeTeleopConfig c;
    c.gains = {60, 60};
    c.prediction = {true, 0.01};
    c.stale_timeout = 0.5;  // real threads on a busy VM: do not fault on a scheduling hiccup
    return c;
  }
  saw::drivers::SimHapticDevice master, slave;
  saw::teleop::DelayTask delay;
  saw::teleop::Teleoperation teleop;
  saw::Manager m;
};

// The bilateral laws under delay: the master's port between the master and the link, the slave
// against a wall; time-domain passivity at both ports, or wave variables.
struct BilateralDeployment {
  explicit BilateralDeployment(bool waves = false)
      : master("master", saw::TaskConfig::periodic(1ms, 0), Deployment::master_config()),
        slave("slave", saw::TaskConfig::periodic(1ms, 0), slave_config()),
        port("port", saw::TaskConfig::periodic(1ms, 0), port_config(waves)),
        delay("master_delay", saw::TaskConfig::periodic(1ms, 0), Deployment::link_config()),
        teleop("teleop", saw::TaskConfig::periodic(1ms, 0), teleop_config(),
               waves ? saw::teleop::law_spec<saw::teleop::WaveVariableLaw>()
                     : saw::teleop::law_spec<saw::teleop::PassiveBilateralLaw>()) {
    for (saw::Component* c : std::initializer_list<saw::Component*>{&master, &slave, &port, &delay, &teleop})
      m.add(*c);
    m.connect("port", "device", "master", "arm");
    m.connect("master_delay", "source", "port", "arm");
    m.connect("teleop", "master", "master_delay", "arm");
    m.connect("teleop", "slave", "slave", "arm");
  }
  static saw::drivers::SimDeviceConfig slave_config() {
    saw::drivers::SimDeviceConfig c;
    c.wall.enabled = true;
    c.wall.point = Eigen::Vector3d(0.01, 0, 0);
    c.wall.normal = Eigen::Vector3d(-1, 0, 0);
    c.wall.stiffness = 100;
    return c;
  }
  static saw::teleop::TeleopConfig teleop_config() {
    saw::teleop::TeleopConfig c;
    c.stale_timeout = 0.5;
    return c;
  }
  static saw::teleop::PortConfig port_config(bool waves) {
    saw::teleop::PortConfig c;
    if (waves) c.scheme = saw::teleop::PortScheme::wave;
    return c;
  }
  saw::drivers::SimHapticDevice master, slave;
  saw::teleop::PassivityPort port;
  saw::teleop::DelayTask delay;
  saw::teleop::Teleoperation teleop;
  saw::Manager m;
};

// Teleoperation in SE(3): the 6-DOF stylus drives the instrument arm (its inverse kinematics in
// every cycle) with the surgical law, the clutch pressed and released on the way.
struct Se3Deployment {
  Se3Deployment()
      : master("master", saw::TaskConfig::periodic(1ms, 0), master_config()),
        slave("slave", saw::TaskConfig::periodic(1ms, 0), saw::drivers::SimInstrumentConfig{}),
        teleop("teleop", saw::TaskConfig::periodic(1ms, 0), teleop_config(),
               saw::teleop::law_spec<saw::teleop::SurgicalLaw>(law_settings())) {
    for (saw::Component* c : std::initializer_list<saw::Component*>{&master, &slave, &teleop}) m.add(*c);
    m.connect("teleop", "master", "master", "arm");
    m.connect("teleop", "slave", "slave", "arm");
  }
  static saw::drivers::SimDeviceConfig master_config() {
    saw::drivers::SimDeviceConfig c = Deployment::master_config();
    c.stylus = true;
    c.hand.turn_axis = {0, 0.6, 0.8};
    c.hand.turn_amplitude = 0.35;
    c.hand.grip_mean = 0.5;
    c.hand.grip_amplitude = 0.2;
    c.hand.clutch_windows = {{1.0, 1.3}};
    return c;
  }
  static saw::teleop::TeleopConfig teleop_config() {
    saw::teleop::TeleopConfig c;
    c.slave_servo_cp = true;
    c.stale_timeout = 0.5;
    return c;
  }
  static saw::teleop::SurgicalLaw::Settings law_settings() {
    saw::teleop::SurgicalLaw::Settings s;
    s.scale = 0.2;
    return s;
  }
  saw::drivers::SimHapticDevice master;
  saw::drivers::SimInstrument slave;
  saw::teleop::Teleoperation teleop;
  saw::Manager m;
};

TEST(RtGuard, TeleoperationInSE3SteppedIsRtClean) {
  saw::testing::GuardWindow window;
  Se3Deployment d;
  d.m.start_stepped();
  d.m.step_until(3'000'000'000);
  const auto counts = window.counts();
  EXPECT_EQ(d.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_GT(d.slave.summary().poses, 2000u) << "the instrument should be following the stylus";
  d.m.stop();
  EXPECT_EQ(counts.cycles, 3 * 3001u);
  EXPECT_RT_CLEAN(counts);
}

template <class D>
double slave_travel(const D& d) {
  std::array<saw::Pose, 200> h;
  const auto n = d.slave.state_table().read_history(d.slave.columns().measured_cp, std::span<saw::Pose>(h));
  double lo = 1, hi = -1;
  for (std::size_t i = 0; i < n; ++i)
    lo = std::min(lo, h[i].position[0]), hi = std::max(hi, h[i].position[0]);
  return hi - lo;
}

TEST(RtGuard, SimulatedTeleoperationSteppedIsRtClean) {
  saw::testing::GuardWindow window;
  Deployment d;
  d.m.start_stepped();
  d.m.step_until(3'000'000'000);
  const auto counts = window.counts();
  EXPECT_EQ(d.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_GT(slave_travel(d), 0.001) << "the slave should be following the master";
  d.m.stop();
  EXPECT_EQ(counts.cycles, 4 * 3001u);
  EXPECT_RT_CLEAN(counts);
}

TEST(RtGuard, SimulatedTeleoperationOnThreadsIsRtClean) {
  saw::testing::GuardWindow window;
  Deployment d;
  saw::testing::run_threads_until(d.m, [&] { return d.teleop.statistics().cycles >= 500; });
  const auto counts = window.counts();
  ASSERT_GE(d.teleop.statistics().cycles, 500u);
  // statistics() is the newest state row, which the last cycle's accounting may not be in yet.
  const auto ran = d.master.statistics().cycles + d.slave.statistics().cycles + d.delay.statistics().cycles +
                   d.teleop.statistics().cycles;
  EXPECT_GE(counts.cycles, ran) << "the guard did not sample every cycle";
  EXPECT_LE(counts.cycles, ran + 4);
  EXPECT_RT_CLEAN(counts);
}

class BilateralGuard : public ::testing::TestWithParam<bool> {};

TEST_P(BilateralGuard, SteppedIsRtClean) {
  saw::testing::GuardWindow window;
  BilateralDeployment d(GetParam());
  d.m.start_stepped();
  d.m.step_until(3'000'000'000);
  {
    // What an exporter does with the link in an RT cycle: its reads that need no row, the port's
    // wave impedance read through and the description of what it carries.
    saw::RtContextScope rt;
    double b = -1;
    saw::ComponentDescription what;
    const auto& arm = *d.delay.provided("arm");
    EXPECT_EQ(arm.find_command(saw::teleop::port::wave_impedance.name)->read(nullptr, &b), saw::Status::ok);
    EXPECT_EQ(arm.find_command("description")->read(nullptr, &what), saw::Status::ok);
    EXPECT_EQ(b, GetParam() ? 2.0 : 0.0);
  }
  const auto counts = window.counts();
  EXPECT_EQ(d.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_GT(slave_travel(d), 0.001) << "the slave should be following the master";
  if (!GetParam()) {
    EXPECT_GT(d.port.controller().energy().in + d.port.controller().energy().out, 0) << "the port observed";
  }
  d.m.stop();
  EXPECT_EQ(counts.cycles, 5 * 3001u);
  EXPECT_RT_CLEAN(counts);
}

TEST_P(BilateralGuard, OnThreadsIsRtClean) {
  saw::testing::GuardWindow window;
  BilateralDeployment d(GetParam());
  saw::testing::run_threads_until(d.m, [&] { return d.teleop.statistics().cycles >= 500; });
  const auto counts = window.counts();
  ASSERT_GE(d.teleop.statistics().cycles, 500u);
  const auto ran = d.master.statistics().cycles + d.slave.statistics().cycles + d.port.statistics().cycles +
                   d.delay.statistics().cycles + d.teleop.statistics().cycles;
  EXPECT_GE(counts.cycles, ran) << "the guard did not sample every cycle";
  EXPECT_LE(counts.cycles, ran + 5);
  EXPECT_RT_CLEAN(counts);
}

INSTANTIATE_TEST_SUITE_P(RtGuard, BilateralGuard, ::testing::Values(false, true),
                         [](const auto& p) { return p.param ? "WaveVariables" : "TimeDomainPassivity"; });

// The wave law's every-cycle check of its port's impedance, through to the FAULT it raises when
// the port answers with another b (its reason written, logged) and when the port stops answering:
// RT-clean from the first cycle. The port is a fake whose b the test changes between cycles.
TEST(RtGuard, AWavePortsImpedanceChangingMidRunFaultsRtClean) {
  for (const saw::Status answer : {saw::Status::ok, saw::Status::disconnected}) {
    saw::testing::FakeWavePort port{"port", 2};
    saw::testing::FakeDevice slave{"slave"};
    saw::teleop::WaveVariableLaw::Settings ls;
    ls.impedance = 2;
    saw::teleop::Teleoperation teleop("teleop", saw::TaskConfig::periodic(1ms, 0),
                                      saw::teleop::TeleopConfig{},
                                      saw::teleop::law_spec<saw::teleop::WaveVariableLaw>(ls));
    saw::Manager m;
    m.add(port);
    m.add(slave);
    m.add(teleop);
    m.connect("teleop", "master", "port", "arm");
    m.connect("teleop", "slave", "slave", "arm");
    m.start_stepped();
    saw::testing::Stepper step{m};
    saw::testing::GuardWindow window;
    for (int i = 0; i < 200; ++i) {
      port.velocity = {0.01, 0, 0};
      port.set_wave({0.1, 0, 0});
      if (i == 100) answer == saw::Status::ok ? void(port.impedance = 3) : void(port.answer = answer);
      step({&port, &slave});
    }
    const auto counts = window.counts();
    EXPECT_EQ(teleop.operating_state(), saw::OperatingStateValue::fault);
    EXPECT_EQ(teleop.fault().code,
              answer == saw::Status::ok ? saw::FaultCode::config_mismatch : saw::FaultCode::input_stale);
    EXPECT_FALSE(teleop.fault_reason().empty());
    m.stop();
    EXPECT_EQ(counts.cycles, 200u);
    EXPECT_RT_CLEAN(counts);
  }
}

}  // namespace
