// A CanopenArm on an in-memory bus with in-process drives, stepped deterministically: each cycle
// the arm (receive, decide, RPDOs, SYNC), then the drives (their TPDOs for the next cycle).
#pragma once

#include <map>
#include <memory>
#include <string>

#include "rig.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/detail/access.hpp"
#include "saw/detail/mailbox.hpp"

namespace saw::canopen::test {

// An Omni-like chain: base yaw (z), shoulder pitch (y), elbow pitch (y) 133 mm out, tip 133 mm further.
inline ChainSpec omni_chain() {
  ChainSpec c;
  c.joints.resize(3);
  c.joints[0].axis = {0, 0, 1};
  c.joints[1].axis = {0, 1, 0};
  c.joints[2].axis = {0, 1, 0};
  c.joints[2].xyz = {0.133, 0, 0};
  c.tip_xyz = {0.133, 0, 0};
  return c;
}

inline CanopenArmConfig arm_config(cia402::Mode mode, std::size_t joints = 3) {
  CanopenArmConfig c;
  c.bus = "test";
  c.mode = mode;
  const char* names[] = {"yaw", "shoulder_pitch", "elbow_pitch"};
  for (std::size_t i = 0; i < joints; ++i) {
    JointConfig j;
    j.name = names[i % 3];
    j.node = static_cast<std::uint8_t>(i + 1);
    j.units = DriveUnits::rotary(4096, 1, 0.5);
    j.min = -2;
    j.max = 2;
    j.max_velocity = 4;
    j.following_error = 0.2;
    c.joints.push_back(j);
  }
  if (joints == 3) c.chain = omni_chain();
  c.heartbeat_period = 10 * ms;
  c.heartbeat_timeout = 30 * ms;
  c.contract.command_timeout = 5 * ms;
  return c;
}

// What the manager queues for a write command: its execute, run in the arm's cycle.
inline detail::Invoker execute_of(Command& c) {
  return {[](void* self, const void* arg) { static_cast<Command*>(self)->execute(arg); }, &c};
}

struct ArmRig {
  explicit ArmRig(CanopenArmConfig c, TestDriveConfig drive = {}) : port(network.attach("arm bus")) {
    for (const JointConfig& j : c.joints) {
      TestDriveConfig d = drive;
      d.node = j.node;
      drives.list.push_back(std::make_unique<TestDrive>(network, d));
    }
    c.startup_pause = [this] {
      drives.step(now);
      now += ms;
      port.now = now;
      return now;
    };
    arm = std::make_unique<CanopenArm>("arm", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c, port);
    // Commands go through a mailbox, as from a connected client: run at the start of the next
    // cycle, stamped with its time.
    detail::Access::add_inbound(*arm, &mailbox);
    for (const char* name : {"servo_jp", "servo_jv", "servo_jf", "state_command"})
      targets[name] = mailbox.add_target(execute_of(command(name)));
    if (arm->provided("arm")->find_command("servo_cf") != nullptr)
      targets["servo_cf"] = mailbox.add_target(execute_of(command("servo_cf")));
    arm->state_table().finalize();
    arm->startup();
  }
  void cycle(int n = 1) {
    for (int i = 0; i < n; ++i) {
      port.now = now;
      detail::Access::step(*arm, now);
      drives.step(now);
      now += ms;
    }
  }
  // Cycles until `done` (at most `limit`); returns the cycles it took.
  template <class Done>
  int cycle_until(Done done, int limit = 1000) {
    int n = 0;
    while (!done() && n < limit) {
      cycle();
      ++n;
    }
    return n;
  }
  Command& command(const std::string& name, const std::string& iface = "arm") {
    Command* c = arm->provided(iface)->find_command(name);
    if (c == nullptr) throw std::logic_error("no command " + name);
    return *c;
  }
  // Queued for the next cycle.
  template <class T>
  void write(const std::string& name, const T& value) {
    if (mailbox.push(targets.at(name), &value, sizeof value) != Status::ok)
      throw std::logic_error("mailbox full");
  }
  void state_command(StateCommand c) { write("state_command", c); }
  template <class T>
  T read(const std::string& name, const std::string& iface = "arm") {
    T v{};
    (void)command(name, iface).read(nullptr, &v);
    return v;
  }
  OperatingStateValue state() { return arm->operating_state().state; }
  void enable() {
    state_command(StateCommand::enable);
    cycle_until([&] { return state() == OperatingStateValue::enabled; }, 100);
  }
  JointState joints(double a, double b, double c) const {
    JointState js;
    js.size = 3;
    js.position = js.velocity = js.effort = {a, b, c};
    return js;
  }

  RingNetwork network;
  detail::Mailbox mailbox{"test client", 64, sizeof(JointState)};
  std::map<std::string, std::uint32_t> targets;
  RingPort& port;
  Drives drives{network, {}};
  std::unique_ptr<CanopenArm> arm;
  TimeNs now = 0;
};

}  // namespace saw::canopen::test
