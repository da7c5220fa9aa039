// Wave variables: the transform's power identity at both ends, a lost wave brings nothing, the
// master port makes its force from the returning wave, the delay task delivers a wave once, and
// the task checks the port's impedance at start-up and every cycle.
#include "saw/teleop/wave.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "port_chain.hpp"
#include "saw/eigen.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/laws/wave_variables.hpp"
#include "saw/teleop/passivity_port.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/fake_wave_port.hpp"
#include "saw/testing/law_io.hpp"
#include "saw/testing/stepper.hpp"

namespace {

using saw::Status;
using saw::teleop::LawInputs;
using saw::teleop::WaveVariableLaw;
using V = Eigen::Vector3d;
namespace port = saw::teleop::port;

TEST(WaveTransform, ThePowerIntoTheNetworkIsHalfTheWavesSquaresDifference) {
  const double b = 3;
  const V velocity(0.1, -0.05, 0.02), v(0.3, 0.1, -0.2);
  const auto end = saw::teleop::wave::master_end(b, velocity, v, 100);
  const V resist = -end.force;
  EXPECT_NEAR(velocity.dot(resist), 0.5 * end.u.squaredNorm() - 0.5 * v.squaredNorm(), 1e-12);
  // Limited: the force is the limit's, and u is made from the force applied.
  const auto limited = saw::teleop::wave::master_end(b, velocity, V(10, 0, 0), 0.5);
  EXPECT_NEAR(limited.force.norm(), 0.5, 1e-12);
  EXPECT_TRUE(limited.u.isApprox((b * velocity - limited.force) / std::sqrt(2 * b)));
}

// The master port's wave u in, v out (the law's declared input and output).
saw::testing::LawIo<saw::Vec3, saw::Vec3> law_port;

LawInputs wave_in(V slave, V slave_velocity, V u, bool fresh) {
  LawInputs in;
  in.slave.position = slave;
  in.slave.velocity = slave_velocity;
  law_port.value = saw::to_vec3(u);
  law_port.fresh = fresh;
  law_port.attach(in);
  return in;
}

V sent_wave() { return law_port.sent() != nullptr ? saw::to_eigen(*law_port.sent()) : V::Constant(NAN); }

TEST(WaveVariableLaw, TheSlavesEndKeepsThePowerIdentityAndALostWaveBringsNothing) {
  WaveVariableLaw law({}, saw::teleop::LawContext{});
  law.reset(wave_in(V::Zero(), V::Zero(), V::Zero(), false));
  const double b = law.settings().impedance, dt = 0.001;
  V desired = V::Zero();
  for (int k = 0; k < 50; ++k) {
    const V u(0.2, 0, 0.1);
    const auto out = law.step(wave_in(V::Zero(), V::Zero(), u, true));
    ASSERT_NE(law_port.sent(), nullptr);
    // The slave's desired velocity is what the wave and the force imply; the power out of the
    // network at the slave is F·ẋ_d = ½|u|² − ½|v|².
    const V xd_dot = (std::sqrt(2 * b) * u - out.slave_force) / b;
    EXPECT_NEAR(out.slave_force.dot(xd_dot), 0.5 * u.squaredNorm() - 0.5 * sent_wave().squaredNorm(), 1e-12);
    desired += dt * xd_dot;
  }
  EXPECT_GT(desired.x(), 0) << "the wave moves the slave's goal";
  // No new wave this cycle: a zero wave, whatever the last one was: v = −√(2/b)·F.
  const auto lost = law.step(wave_in(V::Zero(), V::Zero(), V(5, 5, 5), false));
  EXPECT_TRUE(sent_wave().isApprox(-lost.slave_force * (std::sqrt(2 * b) / b)));
  EXPECT_LT(lost.slave_force.norm(), 3.0 + 1e-12);
}

// A port in the wave scheme between a device and a far side that sends waves.
class WaveFarSide : public saw::Component {
 public:
  WaveFarSide() : Component("far") {
    auto& r = require("arm");
    saw::crtk::require(r, port::wave, wave);
    saw::crtk::require(r, port::remote_wave, remote_wave);
    saw::crtk::require(r, saw::crtk::arm::servo_cf, servo_cf);
  }
  saw::FunctionRead<saw::Vec3> wave;
  saw::FunctionWrite<saw::Vec3> remote_wave;
  saw::FunctionWrite<saw::Wrench> servo_cf;
};

TEST(PassivityPort, TheWaveSchemeMakesTheForceFromTheReturningWaveAndStopsWithoutOne) {
  saw::teleop::PortConfig c;
  c.scheme = saw::teleop::PortScheme::wave;
  c.wave_impedance = 2;
  PortChain<WaveFarSide> rig(c);
  auto& device = rig.device;
  auto& far = rig.far;
  auto& stepper = rig.stepper;
  device.velocity = {0.1, 0, 0};
  stepper({&device});
  stepper({&device});
  saw::Vec3 u{};
  ASSERT_EQ(far.wave(u), Status::ok);
  EXPECT_NEAR(u[0], std::sqrt(2 * 2.0) * 0.1, 1e-12) << "u = √(2b)·ẋ with nothing back";
  EXPECT_EQ(device.commands, 0) << "no wave has arrived: nothing is written";
  ASSERT_EQ(far.servo_cf(saw::Wrench{{9, 9, 9}, {}}), Status::ok);  // ignored in this scheme
  ASSERT_EQ(far.remote_wave(saw::Vec3{0.05, 0, 0}), Status::ok);
  stepper({&device});
  EXPECT_NEAR(device.force[0], -(2.0 * 0.1 - std::sqrt(4.0) * 0.05), 1e-12);
  EXPECT_EQ(device.force[1], 0);
  const int before = device.commands;
  for (int i = 0; i < 20; ++i) stepper({&device});
  EXPECT_LE(device.commands - before, 5) << "without waves the port stops writing after command_hold";
}

TEST(DelayTask, AWaveIsDeliveredOnceInTheCycleItArrivesNeverRepeated) {
  saw::teleop::DelayConfig dc;
  dc.measured = {0, 0, 0, 1};
  dc.commands = {5'000'000, 0, 0, 2};
  saw::teleop::PortConfig pc;
  pc.scheme = saw::teleop::PortScheme::wave;
  PortChain<WaveFarSide> rig(pc, dc);
  auto& device = rig.device;
  auto& far = rig.far;
  auto& stepper = rig.stepper;
  // One wave, with one command, then only commands: the port applies the wave in one cycle only.
  ASSERT_EQ(far.remote_wave(saw::Vec3{0.5, 0, 0}), Status::ok);
  ASSERT_EQ(far.servo_cf(saw::Wrench{}), Status::ok);
  std::vector<double> forces;
  for (int k = 0; k < 15; ++k) {
    if (k > 0) {
      ASSERT_EQ(far.servo_cf(saw::Wrench{}), Status::ok);
    }
    const int before = device.commands;
    stepper({&device});
    if (device.commands > before) forces.push_back(device.force[0]);
  }
  ASSERT_FALSE(forces.empty()) << "the wave arrived after the link's delay";
  EXPECT_NEAR(forces.front(), std::sqrt(4.0) * 0.5, 1e-12) << "the wave's force, the device at rest";
  for (std::size_t i = 1; i < forces.size(); ++i) EXPECT_EQ(forces[i], 0) << "then a zero wave: " << i;
}

TEST(DelayTask, AWaveInFlightIsNotDeliveredToAPortThatNowAnswersAnotherImpedance) {
  saw::testing::FakeWavePort source{"port", 3};
  saw::teleop::DelayConfig dc;
  dc.measured = {0, 0, 0, 1};
  dc.commands = {5'000'000, 0, 0, 2};
  saw::teleop::DelayTask link("link", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0), dc);
  WaveFarSide far;
  saw::Manager manager;
  manager.add(source);
  manager.add(link);
  manager.add(far);
  manager.connect("link", "source", "port", "arm");
  manager.connect("far", "arm", "link", "arm");
  manager.start_stepped();
  saw::testing::Stepper stepper{manager};
  // A wave each cycle, sent while the port says b = 3; 3 cycles in, the port restarts with b = 2.
  for (int k = 0; k < 12; ++k) {
    if (k < 3) {
      ASSERT_EQ(far.remote_wave(saw::Vec3{0.5, 0, 0}), Status::ok);
      ASSERT_EQ(far.servo_cf(saw::Wrench{}), Status::ok);
    }
    if (k == 3) source.impedance = 2;
    stepper({&source});
  }
  EXPECT_EQ(source.waves, 0) << "the waves made for b = 3 reached the port with b = 2";
  EXPECT_EQ(link.waves_dropped(), 3u);
  // Sent and delivered with the same b: delivered.
  for (int k = 0; k < 12; ++k) {
    if (k < 3) {
      ASSERT_EQ(far.remote_wave(saw::Vec3{0.5, 0, 0}), Status::ok);
      ASSERT_EQ(far.servo_cf(saw::Wrench{}), Status::ok);
    }
    stepper({&source});
  }
  EXPECT_EQ(source.waves, 3);
  EXPECT_EQ(link.waves_dropped(), 3u);
}

// A wave law between a master behind its port (and a link) and a slave: how the task starts.
struct WaveTeleop {
  // port_b: the port's wave_impedance (scheme wave), or 0 for a port in the passivity scheme, or
  // -1 for no port at all (the link's source is the device).
  WaveTeleop(double port_b, double law_b) {
    saw::teleop::PortConfig pc;
    pc.scheme = port_b > 0 ? saw::teleop::PortScheme::wave : saw::teleop::PortScheme::passivity;
    if (port_b > 0) pc.wave_impedance = port_b;
    port.emplace("port", period(), pc);
    link.emplace("link", period(), saw::teleop::DelayConfig{{20'000'000, 0, 0, 1}, {20'000'000, 0, 0, 2}, 0});
    WaveVariableLaw::Settings ls;
    ls.impedance = law_b;
    teleop.emplace("teleop", period(), saw::teleop::TeleopConfig{},
                   saw::teleop::law_spec<WaveVariableLaw>(ls));
    for (saw::Component* c : {static_cast<saw::Component*>(&master), static_cast<saw::Component*>(&slave),
                              static_cast<saw::Component*>(&*port), static_cast<saw::Component*>(&*link),
                              static_cast<saw::Component*>(&*teleop)})
      manager.add(*c);
    manager.connect("port", "device", "master", "arm");
    manager.connect("link", "source", port_b >= 0 ? "port" : "master", "arm");
    manager.connect("teleop", "master", "link", "arm");
    manager.connect("teleop", "slave", "slave", "arm");
  }
  static saw::TaskConfig period() { return saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0); }
  // The StartError's text, or "" when the deployment started.
  std::string start() {
    try {
      manager.start_stepped();
    } catch (const saw::StartError& e) {
      return e.what();
    }
    return "";
  }

  saw::testing::FakeDevice master{"master"}, slave{"slave"};
  std::optional<saw::teleop::PassivityPort> port;
  std::optional<saw::teleop::DelayTask> link;
  std::optional<saw::teleop::Teleoperation> teleop;
  saw::Manager manager;
};

TEST(PassivityPort, SaysItsWaveImpedanceBeforeItsFirstCycleAndZeroOutsideTheWaveScheme) {
  saw::teleop::PortConfig c;
  c.scheme = saw::teleop::PortScheme::wave;
  c.wave_impedance = 3.5;
  saw::teleop::PassivityPort wave_port("port", WaveTeleop::period(), c);
  double b = -1;
  const saw::Command* read = wave_port.provided("arm")->find_command(port::wave_impedance.name);
  ASSERT_NE(read, nullptr);
  ASSERT_EQ(read->read(nullptr, &b), Status::ok) << "no row needed: the port has not run";
  EXPECT_EQ(b, 3.5);
  c.scheme = saw::teleop::PortScheme::passivity;
  saw::teleop::PassivityPort tdpa_port("port", WaveTeleop::period(), c);
  ASSERT_EQ(tdpa_port.provided("arm")->find_command(port::wave_impedance.name)->read(nullptr, &b),
            Status::ok);
  EXPECT_EQ(b, 0) << "time-domain passivity has no wave impedance";
}

TEST(WaveVariableLaw, TheTaskStartsItWhenThePortsImpedanceIsTheLaws) {
  WaveTeleop rig(3, 3);
  EXPECT_EQ(rig.start(), "");
  // Through the link, undelayed: a setting, not a signal.
  double b = 0;
  ASSERT_EQ(rig.link->provided("arm")->find_command(port::wave_impedance.name)->read(nullptr, &b),
            Status::ok);
  EXPECT_EQ(b, 3);
}

TEST(WaveVariableLaw, TheTaskRefusesToStartItWhenThePortsImpedanceDiffersNamingBoth) {
  WaveTeleop rig(2, 3);
  const std::string why = rig.start();
  ASSERT_FALSE(why.empty()) << "a wave channel with b = 3 at the slave and b = 2 at the master started";
  EXPECT_NE(why.find("component 'teleop'"), std::string::npos) << why;
  EXPECT_NE(why.find("impedance 3 N·s/m"), std::string::npos) << why;
  EXPECT_NE(why.find("port_wave_impedance from the master ('port.arm', through 'link.arm') is 2 N·s/m"),
            std::string::npos)
      << why;
  EXPECT_EQ(why.find('\n'), std::string::npos) << "one line: " << why;
  EXPECT_EQ(rig.master.commands, 0) << "nothing was driven";
  // Different past the digits a setting is shown with: still refused, and shown apart.
  const std::string close = WaveTeleop(3 + 1e-9, 3).start();
  EXPECT_NE(close.find("is 3.000000001"), std::string::npos) << close;
}

TEST(WaveVariableLaw, TheTaskRefusesToStartItWithAPortInThePassivitySchemeOrNoPort) {
  const std::string passivity = WaveTeleop(0, 3).start();
  EXPECT_NE(passivity.find("is 0 N·s/m"), std::string::npos) << passivity;
  EXPECT_NE(passivity.find("runs time-domain passivity"), std::string::npos) << passivity;
  const std::string none = WaveTeleop(-1, 3).start();
  EXPECT_NE(none.find("port_wave_impedance from the master ('master.arm', through 'link.arm') gives none"),
            std::string::npos)
      << none;
}

TEST(WaveVariableLaw, ItsImpedanceIsFixedByTheDeploymentNotSetAtRunTime) {
  // Changing b at one end mid-run makes the channel non-passive: no set_impedance, only the read.
  WaveTeleop rig(2, 2);
  ASSERT_EQ(rig.start(), "");
  const saw::ProvidedInterface& p = *rig.teleop->provided("teleop");
  EXPECT_EQ(p.find_command("set_impedance"), nullptr);
  EXPECT_NE(p.find_command("set_stiffness"), nullptr) << "the other settings still are";
  double b = 0;
  ASSERT_NE(p.find_command("impedance"), nullptr);
  saw::testing::Stepper stepper{rig.manager};
  stepper({&rig.master, &rig.slave});
  ASSERT_EQ(p.find_command("impedance")->read(nullptr, &b), Status::ok);
  EXPECT_EQ(b, 2);
}

double norm3(const saw::Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// A wave law driving a slave from a master port whose impedance the test changes mid-run (what a
// port restarted with another b looks like through the bridge), on the stepped clock.
struct RunningWaveTeleop {
  // Sends the task its state commands (enable after a fault).
  struct Operator : saw::Component {
    Operator() : Component("operator") { require("teleop").add_function("state_command", state_command); }
    saw::FunctionWrite<saw::StateCommand> state_command;
  };
  explicit RunningWaveTeleop(double stale_timeout = 0.01) {
    WaveVariableLaw::Settings ls;
    ls.impedance = 3;
    saw::teleop::TeleopConfig tc;
    tc.stale_timeout = stale_timeout;
    teleop.emplace("teleop", WaveTeleop::period(), tc, saw::teleop::law_spec<WaveVariableLaw>(ls));
    manager.add(port);
    manager.add(slave);
    manager.add(*teleop);
    manager.add(op);
    manager.connect("teleop", "master", "port", "arm");
    manager.connect("teleop", "slave", "slave", "arm");
    manager.connect("operator", "teleop", "teleop", "teleop");
    manager.start_stepped();
  }
  // n cycles, the master moving and its port sending a wave each row.
  void step(int n = 1) {
    for (int i = 0; i < n; ++i) {
      port.velocity = {0.01, 0, 0};
      port.set_wave({0.2, 0, 0});
      stepper({&port, &slave});
    }
  }

  saw::testing::FakeWavePort port{"port", 3};
  saw::testing::FakeDevice slave{"slave"};
  std::optional<saw::teleop::Teleoperation> teleop;
  Operator op;
  saw::Manager manager;
  saw::testing::Stepper stepper{manager};
};

TEST(WaveVariableLaw, APortWhoseImpedanceChangesMidRunFaultsTheTaskBeforeItsWaveIsUsed) {
  RunningWaveTeleop rig;
  rig.step(20);
  ASSERT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::enabled);
  ASSERT_GT(rig.port.waves, 0) << "the law sends its waves to the port";
  ASSERT_GT(norm3(rig.slave.force), 0) << "and drives the slave from the port's";
  const int waves = rig.port.waves, slave_commands = rig.slave.commands;

  // The port restarted with b = 2: its very first wave (made with b = 2) is not used.
  rig.port.impedance = 2;
  rig.step();
  EXPECT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::fault);
  const saw::teleop::FaultInfo& f = rig.teleop->fault();
  EXPECT_EQ(f.code, saw::FaultCode::config_mismatch);
  EXPECT_EQ(f.source_name(), "master");
  const std::string why(rig.teleop->fault_reason());
  EXPECT_NE(why.find("law 'wave_variables' has impedance 3 N·s/m"), std::string::npos) << why;
  EXPECT_NE(why.find("port_wave_impedance from the master ('port.arm') is now 2 N·s/m"), std::string::npos)
      << why;
  EXPECT_EQ(why.find('\n'), std::string::npos) << "one line: " << why;
  // The devices as for any fault: zero force to both, no wave to the port, from that cycle on.
  EXPECT_EQ(rig.port.waves, waves) << "no wave was sent to the port with the other b";
  EXPECT_GT(rig.slave.commands, slave_commands);
  EXPECT_EQ(norm3(rig.slave.force), 0) << "the slave got no force made from that wave";
  EXPECT_EQ(norm3(rig.port.force), 0);
  rig.step(10);
  EXPECT_EQ(rig.port.waves, waves);
  EXPECT_EQ(norm3(rig.slave.force), 0);
  saw::teleop::TeleopSummary summary;
  ASSERT_EQ(rig.teleop->state_table().read_latest(rig.teleop->columns().summary, summary), Status::ok);
  const std::string said = saw::teleop::to_string(summary);
  EXPECT_NE(said.find("master configuration mismatch"), std::string::npos) << said;
  EXPECT_NE(said.find("is now 2 N·s/m"), std::string::npos) << said;

  // Re-enabled with the other b still there: FAULT again at once. With the law's b back: it runs.
  ASSERT_EQ(rig.op.state_command(saw::StateCommand::enable), Status::ok);
  rig.step();
  EXPECT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.port.waves, waves);
  rig.port.impedance = 3;
  ASSERT_EQ(rig.op.state_command(saw::StateCommand::enable), Status::ok);
  rig.step(5);
  EXPECT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_EQ(rig.teleop->fault_reason(), "");
  EXPECT_GT(rig.port.waves, waves);
}

TEST(WaveVariableLaw, APortNowInThePassivitySchemeOrSilentFaultsTheTaskSayingSo) {
  {
    RunningWaveTeleop rig;
    rig.step(20);
    ASSERT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::enabled);
    rig.port.impedance = 0;  // restarted with scheme: passivity
    rig.step();
    EXPECT_EQ(rig.teleop->fault().code, saw::FaultCode::config_mismatch);
    const std::string why(rig.teleop->fault_reason());
    EXPECT_NE(why.find("is now 0 N·s/m"), std::string::npos) << why;
    EXPECT_NE(why.find("impedance 3 N·s/m"), std::string::npos) << why;
  }
  // A port that stops answering its impedance (its process gone, the bridge disconnected) fails
  // the input as a silent device does: held for stale_timeout, then FAULT; meanwhile no wave is
  // sent or used and both forces are zero, as with the clutch.
  RunningWaveTeleop rig(0.005);
  rig.step(20);
  const int waves = rig.port.waves;
  rig.port.answer = Status::disconnected;
  rig.step(3);
  EXPECT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::enabled) << "within stale_timeout";
  EXPECT_EQ(rig.port.waves, waves) << "no wave while the port's b is unknown";
  EXPECT_EQ(norm3(rig.slave.force), 0);
  rig.step(5);
  EXPECT_EQ(rig.teleop->operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop->fault().code, saw::FaultCode::input_stale);
  EXPECT_EQ(rig.teleop->fault().last_read, Status::disconnected);
  const std::string why(rig.teleop->fault_reason());
  EXPECT_NE(why.find("port_wave_impedance from the master ('port.arm') no longer answers (disconnected)"),
            std::string::npos)
      << why;
}

}  // namespace
