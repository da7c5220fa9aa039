// The device base (saw/device.hpp) with a scripted driver: what the contract does whatever the
// hardware says — throws, errors, enables that never finish, homing that times out, a failed
// start among others.
#include "saw/device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "saw/detail/access.hpp"
#include "saw/detail/mailbox.hpp"
#include "saw/manager.hpp"

namespace saw {
namespace {

// A driver whose every hardware call does what the test scripted, and which records what it
// was asked.
class ScriptedDevice : public Device {
 public:
  explicit ScriptedDevice(std::string name = "dev", DeviceConfig c = config())
      : Device(std::move(name), TaskConfig::periodic(std::chrono::milliseconds(1), 0), std::move(c)) {}
  static DeviceConfig config() {
    DeviceConfig c;
    c.max_force = 5;
    c.start_enabled = false;
    c.enable_timeout = 10'000'000;
    c.home_timeout = 20'000'000;
    c.joints = {JointLimits{"a"}, JointLimits{"b"}, JointLimits{"c"}};
    return c;
  }

  // The script.
  bool throw_on_open = false, throw_on_read = false, enable_never = false, home_never = false;
  Outcome read_result = Outcome::done();
  // What it was asked.
  Setpoint last{};
  int writes = 0, opened = 0, closed = 0;
  std::vector<SafeReason> safe_reasons;

  using Device::measured;
  using Device::update_fault;

 protected:
  void open() override {
    ++opened;
    if (throw_on_open) throw std::runtime_error("port /dev/ttyX does not open");
  }
  void close() noexcept override { ++closed; }
  Outcome read() override {
    if (throw_on_read) throw std::runtime_error("the encoder board went away");
    return read_result;
  }
  Outcome write(const Setpoint& s) override {
    last = s;
    ++writes;
    return Outcome::done();
  }
  Outcome enable() override { return enable_never ? Outcome::pending() : Outcome::done(); }
  Outcome home() override { return home_never ? Outcome::pending() : Outcome::done(); }
  void enter_safe_state(SafeReason why) override { safe_reasons.push_back(why); }
};

class DeviceBase : public testing::Test {
 protected:
  void SetUp() override {
    detail::Access::add_inbound(dev, &mailbox);
    for (const char* n : {"servo_cf", "state_command"}) {
      Command* c = dev.provided("arm")->find_command(n);
      targets[n] = mailbox.add_target(
          {[](void* self, const void* arg) { static_cast<Command*>(self)->execute(arg); }, c});
    }
    dev.state_table().finalize();
  }
  void cycle(int n = 1) {
    for (int i = 0; i < n; ++i, now += 1'000'000) detail::Access::step(dev, now);
  }
  template <class T>
  void write(const char* name, const T& v) {
    ASSERT_EQ(mailbox.push(targets.at(name), &v, sizeof v), Status::ok);
  }
  void enable() {
    write("state_command", StateCommand::enable);
    cycle();
  }
  OperatingStateValue state() const { return dev.operating_state().state; }

  ScriptedDevice dev;
  detail::Mailbox mailbox{"test", 16, sizeof(Wrench)};
  std::map<std::string, std::uint32_t> targets;
  TimeNs now = 1'000'000'000;
};

TEST_F(DeviceBase, ADriverThatThrowsInItsCycleFaultsWithWhatItSaidAndNothingEscapes) {
  dev.startup();
  enable();
  write("servo_cf", Wrench{{1, 0, 0}, {}});
  cycle();
  ASSERT_EQ(dev.last.mode, ServoMode::cf);
  dev.throw_on_read = true;
  cycle();
  EXPECT_EQ(state(), OperatingStateValue::fault);
  EXPECT_EQ(dev.fault().code, FaultCode::device_error);
  EXPECT_EQ(dev.fault().source_name(), "driver");
  EXPECT_EQ(dev.device_status().reason_text(), "the encoder board went away");
  EXPECT_EQ(dev.device_status().origin, saw::FaultOrigin::driver);
  EXPECT_EQ(dev.last.mode, ServoMode::none) << "the same cycle's write already carried the safe output";
  ASSERT_FALSE(dev.safe_reasons.empty());
  EXPECT_EQ(dev.safe_reasons.back(), SafeReason::fault);
}

TEST_F(DeviceBase, AnErrorFromTheHardwareFaultsWithItsReasonOnceAndEnableClearsIt) {
  dev.startup();
  enable();
  dev.read_result = Outcome::failed(FaultCode::device_lost, "no heartbeat", "node 5", 0x1234, 42);
  cycle(3);
  EXPECT_EQ(state(), OperatingStateValue::fault);
  EXPECT_EQ(dev.device_status().faults, 1u) << "the first cause stands; one fault";
  EXPECT_EQ(dev.fault().source_name(), "node 5");
  EXPECT_EQ(dev.fault().detail, 0x1234u);
  EXPECT_EQ(dev.fault().age_ns, 42);
  EXPECT_EQ(dev.device_status().reason_text(), "no heartbeat");
  EXPECT_EQ(dev.device_status().origin, saw::FaultOrigin::driver);
  dev.update_fault(Outcome::failed(FaultCode::device_lost, "node gone", "node 5"));
  EXPECT_EQ(dev.device_status().reason_text(), "node gone");
  EXPECT_EQ(dev.device_status().faults, 1u) << "known better, still one fault";
  // The cause persists: enable clears, then faults again at once.
  enable();
  EXPECT_EQ(state(), OperatingStateValue::fault);
  EXPECT_EQ(dev.device_status().faults, 2u);
  dev.read_result = Outcome::done();
  enable();
  EXPECT_EQ(state(), OperatingStateValue::enabled);
  EXPECT_EQ(dev.fault().code, FaultCode::none);
  EXPECT_EQ(dev.device_status().fault.code, FaultCode::device_lost) << "the last fault is kept in the status";
}

TEST_F(DeviceBase, AnEnableThatNeverCompletesFaultsAtItsTimeoutAndIsBusyUntilThen) {
  dev.startup();
  dev.enable_never = true;
  write("state_command", StateCommand::enable);
  cycle(5);
  EXPECT_EQ(state(), OperatingStateValue::disabled);
  EXPECT_TRUE(dev.operating_state().is_busy);
  write("servo_cf", Wrench{{1, 0, 0}, {}});
  cycle();
  EXPECT_EQ(dev.last.mode, ServoMode::none) << "enabling: no command reaches the hardware";
  cycle(10);
  EXPECT_EQ(state(), OperatingStateValue::fault);
  EXPECT_EQ(dev.device_status().reason_text(), "enable timed out");
  EXPECT_EQ(dev.device_status().origin, saw::FaultOrigin::enable_timeout)
      << "typed: no driver reads the text";
}

TEST_F(DeviceBase, HomingIsBusyAndTimesOut) {
  dev.startup();
  enable();
  dev.home_never = true;
  write("state_command", StateCommand::home);
  cycle(5);
  EXPECT_TRUE(dev.operating_state().is_busy);
  EXPECT_FALSE(dev.following());
  cycle(20);
  EXPECT_EQ(state(), OperatingStateValue::fault);
  EXPECT_EQ(dev.fault().code, FaultCode::limit_exceeded);
  EXPECT_EQ(dev.device_status().reason_text(), "homing timed out");
  EXPECT_EQ(dev.device_status().origin, saw::FaultOrigin::home_timeout);
  dev.home_never = false;
  enable();
  write("state_command", StateCommand::home);
  cycle(2);
  EXPECT_TRUE(dev.operating_state().is_homed);
  EXPECT_FALSE(dev.operating_state().is_busy);
}

TEST(DeviceJoints, JointCommandsAreCheckedAgainstTheDeclaredLimits) {
  DeviceConfig c = ScriptedDevice::config();
  c.servo_cf = false;
  c.servo_jp = true;
  c.joints[1].min = -1;
  c.joints[1].max = 1;
  c.joints[1].max_velocity = 2;  // rad/s: 2 mrad per 1 ms cycle
  ScriptedDevice d("joints", c);
  EXPECT_EQ(d.provided("arm")->find_command("servo_cf"), nullptr) << "not declared, not provided";
  EXPECT_EQ(d.provided("arm")->find_command("servo_jv"), nullptr);
  Command* servo_jp = d.provided("arm")->find_command("servo_jp");
  ASSERT_NE(servo_jp, nullptr);
  d.state_table().finalize();
  d.startup();
  TimeNs t = 1'000'000'000;
  const auto step = [&] { detail::Access::step(d, t), t += 1'000'000; };
  const auto jp = [&](double b, std::uint32_t size = 3) {
    JointState js;
    js.size = size;
    js.position = {0, b, 0};
    servo_jp->execute(&js);  // as the mailbox runs it, before the next cycle
    step();
    return d.last;
  };
  StateCommand enable = StateCommand::enable;
  d.provided("arm")->find_command("state_command")->execute(&enable);
  step();
  ASSERT_TRUE(d.following());
  EXPECT_EQ(jp(0.001).mode, ServoMode::jp);
  EXPECT_EQ(d.last.joints[1], 0.001);
  EXPECT_EQ(jp(0.5).mode, ServoMode::none) << "a step faster than max_velocity";
  EXPECT_EQ(jp(1.5).mode, ServoMode::none) << "beyond max";
  EXPECT_EQ(jp(NAN).mode, ServoMode::none);
  EXPECT_EQ(jp(0.002, 2).mode, ServoMode::none) << "two joints of three";
  EXPECT_EQ(jp(0.002).mode, ServoMode::jp);
  const RefusedCommands& r = d.device_status().refused;
  EXPECT_EQ(r.over_limit, 2u);
  EXPECT_EQ(r.not_finite, 1u);
  EXPECT_EQ(r.wrong_size, 1u);
}

TEST(DeviceCartesian, PoseCommandsAreCheckedAgainstTheWorkspaceAndTheSpeeds) {
  DeviceConfig c = ScriptedDevice::config();
  c.servo_cp = true;
  c.max_linear_speed = 0.2;   // m/s: 0.2 mm per 1 ms cycle
  c.max_angular_speed = 1.0;  // rad/s: 1 mrad per cycle
  c.workspace_min = {-0.1, -0.1, -0.1};
  c.workspace_max = {0.1, 0.1, 0.1};
  ScriptedDevice d("pose", c);
  Command* servo_cp = d.provided("arm")->find_command("servo_cp");
  ASSERT_NE(servo_cp, nullptr);
  d.state_table().finalize();
  d.startup();
  TimeNs t = 1'000'000'000;
  const auto step = [&] { detail::Access::step(d, t), t += 1'000'000; };
  // A pose x m along x, turned `a` rad about z (q = [x, y, z, w]).
  const auto cp = [&](double x, double a = 0, double w_scale = 1) {
    Pose p;
    p.position = {x, 0, 0};
    p.orientation = {0, 0, std::sin(a / 2), w_scale * std::cos(a / 2)};
    servo_cp->execute(&p);
    step();
    return d.last;
  };
  StateCommand enable = StateCommand::enable;
  d.provided("arm")->find_command("state_command")->execute(&enable);
  step();
  ASSERT_TRUE(d.following());
  EXPECT_EQ(cp(0.0001).mode, ServoMode::cp) << "0.1 mm from the measured pose (the origin)";
  EXPECT_EQ(d.last.pose.position[0], 0.0001);
  EXPECT_EQ(cp(0.0002, 0.0005).mode, ServoMode::cp) << "0.1 mm and 0.5 mrad: within both speeds";
  EXPECT_EQ(cp(0.0010, 0.0005).mode, ServoMode::none) << "0.8 mm in a cycle: faster than 0.2 m/s";
  EXPECT_EQ(cp(0.0002, 0.01).mode, ServoMode::none) << "10 mrad in a cycle: faster than 1 rad/s";
  EXPECT_EQ(cp(0.0002, -0.0005).mode, ServoMode::cp)
      << "1 mrad from the last accepted, 3 ms (the command timeout) since";
  EXPECT_EQ(cp(0.0002, -0.0005, 1.1).mode, ServoMode::none) << "not a unit quaternion: no rotation";
  EXPECT_EQ(cp(NAN).mode, ServoMode::none);
  EXPECT_EQ(cp(0.2).mode, ServoMode::none) << "outside the workspace";
  const RefusedCommands& r = d.device_status().refused;
  EXPECT_EQ(r.over_limit, 4u);
  EXPECT_EQ(r.not_finite, 1u);
  // After the refusals the step is judged from the last accepted pose, not the refused ones.
  EXPECT_EQ(cp(0.0003, -0.0005).mode, ServoMode::cp);
  // Commands stopped: the arm holds where it is, not at the last command. The stream resumes from
  // the measured pose (0.05 mm, 20 mrad from the last command), judged over the command timeout.
  for (int k = 0; k < 5; ++k) step();
  ASSERT_EQ(d.device_status().watchdog_trips, 1u);
  d.measured().cp.position = {0.00025, 0, 0};
  d.measured().cp.orientation = {0, 0, std::sin(0.01), std::cos(0.01)};
  EXPECT_EQ(cp(0.00026, 0.0205).mode, ServoMode::cp) << "from where the arm holds, after the pause";
  EXPECT_EQ(cp(0.00027, 0.021).mode, ServoMode::cp) << "then from that accepted pose";
  DeviceConfig plain = ScriptedDevice::config();
  ScriptedDevice p("plain", plain);
  EXPECT_EQ(p.provided("arm")->find_command("servo_cp"), nullptr) << "not declared, not provided";
}

TEST_F(DeviceBase, StartAndStopGoThroughTheSafeState) {
  dev.startup();
  EXPECT_EQ(dev.opened, 1);
  enable();
  write("servo_cf", Wrench{{1, 0, 0}, {}});
  cycle();
  EXPECT_EQ(dev.last.mode, ServoMode::cf);
  dev.cleanup();
  ASSERT_EQ(dev.safe_reasons.size(), 1u);
  EXPECT_EQ(dev.safe_reasons[0], SafeReason::stop);
  EXPECT_EQ(dev.last.mode, ServoMode::none) << "the last output the hardware got is the safe one";
  EXPECT_EQ(dev.closed, 1);
}

TEST(DeviceStart, AFailedStartIsAStartErrorNamingTheDeviceAndTheOthersAreStoppedSafely) {
  Manager m(ManagerOptions{false, false, false});
  auto& first = static_cast<ScriptedDevice&>(m.add(std::make_unique<ScriptedDevice>("first")));
  auto& arm = static_cast<ScriptedDevice&>(m.add(std::make_unique<ScriptedDevice>("arm")));
  auto& last = static_cast<ScriptedDevice&>(m.add(std::make_unique<ScriptedDevice>("last")));
  arm.throw_on_open = true;
  std::string what;
  try {
    m.start_stepped();
  } catch (const StartError& e) {
    what = e.what();
    EXPECT_EQ(e.component(), "arm");
  }
  EXPECT_EQ(what, "component 'arm': port /dev/ttyX does not open");
  ASSERT_EQ(first.safe_reasons.size(), 1u);
  EXPECT_EQ(first.safe_reasons[0], SafeReason::stop) << "started before it: stopped through the safe state";
  EXPECT_EQ(first.closed, 1);
  ASSERT_EQ(arm.safe_reasons.size(), 1u);
  EXPECT_EQ(arm.safe_reasons[0], SafeReason::start_failed);
  EXPECT_EQ(arm.closed, 1);
  EXPECT_EQ(last.opened, 0) << "never started";
  EXPECT_EQ(m.state(), ManagerState::idle);
}

}  // namespace
}  // namespace saw
