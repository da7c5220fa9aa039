// Components on one bus task against in-process drives (and a scripted I/O node) on an in-memory bus.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "arm_rig.hpp"
#include "saw/can/borrowed_bus.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/canopen_io.hpp"
#include "saw/detail/access.hpp"

namespace saw::canopen::test {

// The bus task owns its bus; the network owns the test's ports: a bus that forwards to one.
using Borrowed = can::BorrowedBus;

inline CanopenArmConfig client(const std::string& bus, std::vector<std::uint8_t> nodes) {
  CanopenArmConfig c = arm_config(cia402::csp, nodes.size());
  c.bus = bus;
  c.chain.reset();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    c.joints[i].node = nodes[i];
    c.joints[i].name = "n" + std::to_string(nodes[i]);
  }
  c.contract.start_enabled = true;
  c.feedback_timeout = 20 * ms;
  return c;
}

// A scripted I/O node (CiA 301 only as far as the master's start-up needs it): boot-up on an NMT
// reset, every SDO download acknowledged, NMT start/stop/pre-operational, a heartbeat every
// 10 ms, RPDO1 = one INTEGER16 output, TPDO1 = one INTEGER16 input that follows the output by
// at most 50 counts per SYNC. Fixed memory: it runs inside the RT guard's window.
struct FakeIoNode {
  FakeIoNode(RingNetwork& network, std::uint8_t id) : port(network.attach("io node")), node(id) {}
  void send(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) noexcept {
    const can::Frame f = can::classic(id, std::span<const std::uint8_t>(bytes.begin(), bytes.size()));
    (void)port.send(std::span(&f, 1));
  }
  void step(TimeNs now) noexcept {
    port.now = now;
    can::Received r[64];
    for (std::size_t k; (k = port.receive(r)) > 0;)
      for (std::size_t j = 0; j < k; ++j) on_frame(r[j].frame);
    if (!silent && now >= next_heartbeat) {
      send(0x700u + node, {state});
      next_heartbeat = now + 10 * ms;
    }
  }
  void on_frame(const can::Frame& f) noexcept {
    const std::uint32_t id = f.can_id() & CAN_SFF_MASK;
    if (id == 0 && f.len == 2 && (f.data[1] == node || f.data[1] == 0)) {
      switch (f.data[0]) {
        case 0x81:
        case 0x82:
          state = 0x7F;
          downloads = 0;
          send(0x700u + node, {0x00});  // boot-up
          break;
        case 0x01:
          state = 0x05;
          break;
        case 0x02:
          state = 0x04;
          break;
        case 0x80:
          state = 0x7F;
          break;
        default:
          break;
      }
    } else if (id == 0x600u + node && f.len == 8 && (f.data[0] >> 5) == 2) {  // upload: 0x1000's value
      const bool type = f.data[1] == 0x00 && f.data[2] == 0x10;
      send(0x580u + node,
           {0x43, f.data[1], f.data[2], f.data[3], static_cast<std::uint8_t>(type ? 0x91 : 0),
            static_cast<std::uint8_t>(type ? 0x01 : 0), static_cast<std::uint8_t>(type ? 0x0C : 0), 0});
    } else if (id == 0x600u + node && f.len == 8 && (f.data[0] >> 5) == 1) {
      configured = true;
      ++downloads;
      send(0x580u + node, {0x60, f.data[1], f.data[2], f.data[3], 0, 0, 0, 0});
    } else if (id == 0x200u + node && f.len == 2 && state == 0x05) {
      output = static_cast<std::int16_t>(f.data[0] | f.data[1] << 8);
    } else if (id == 0x080 && state == 0x05 && !silent) {
      input = static_cast<std::int16_t>(input + std::clamp(output - input, -50, 50));
      send(0x180u + node,
           {static_cast<std::uint8_t>(input & 0xFF), static_cast<std::uint8_t>((input >> 8) & 0xFF)});
    }
  }
  // A power cycle: what the master configured is gone; a boot-up, then pre-operational.
  void reboot() noexcept {
    state = 0x7F;
    configured = false;
    downloads = 0;
    send(0x700u + node, {0x00});
  }
  RingPort& port;
  std::uint8_t node;
  bool configured = false;  // an SDO download came since the last reboot
  int downloads = 0;        // SDO downloads since the last reboot or NMT reset
  std::uint8_t state = 0x7F;
  std::int16_t output = 0, input = 0;
  bool silent = false;
  TimeNs next_heartbeat = 0;
};

inline CanopenIoConfig gripper_config(const std::string& bus, std::uint8_t node) {
  CanopenIoConfig c;
  c.bus = bus;
  c.interface_name = "gripper";
  c.node.node = node;
  c.node.heartbeat_period = 10 * ms;
  c.node.heartbeat_timeout = 30 * ms;
  IoChannel jaw;
  jaw.name = "jaw";
  jaw.output = PdoEntry::of({0x6411, 1}, DataType::integer16);
  jaw.input = PdoEntry::of({0x6401, 1}, DataType::integer16);
  jaw.scale = 1e-5;
  jaw.min = 0;
  jaw.max = 0.08;
  jaw.safe = 0.02;
  c.channels.push_back(jaw);
  c.node.pdos.push_back(make_pdo(PdoKind::rpdo, 1, node, std::span(&*jaw.output, 1)));
  c.node.pdos.push_back(make_pdo(PdoKind::tpdo, 1, node, std::span(&*jaw.input, 1)));
  c.contract.start_enabled = true;
  c.feedback_timeout = 20 * ms;
  return c;
}

struct SharedRig {
  SharedRig() : bus_port(network.attach("shared")), spy(network.attach("spy")) {
    BusTaskConfig k;
    k.heartbeat_period = 10 * ms;
    k.heartbeat_timeout = 50 * ms;
    task = std::make_shared<BusTask>(std::make_unique<Borrowed>(bus_port), k);
    publish_bus_task(name, task);
    drives.add(network, {1, 2, 3});
  }
  ~SharedRig() { withdraw_bus_task(name); }
  std::unique_ptr<CanopenArm> make(const std::string& who, std::vector<std::uint8_t> nodes,
                                   const std::function<void(CanopenArmConfig&)>& edit = {}) {
    CanopenArmConfig c = client(name, std::move(nodes));
    if (edit) edit(c);
    c.startup_pause = [this] {
      if (during_startup) during_startup();
      drives.step(now);
      now += ms;
      bus_port.now = now;
      return now;
    };
    auto arm = std::make_unique<CanopenArm>(who, TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    arm->state_table().finalize();
    return arm;
  }
  std::unique_ptr<CanopenIo> make_io(const std::string& who, std::uint8_t node) {
    fake_io = std::make_unique<FakeIoNode>(network, node);
    io_node = fake_io.get();
    CanopenIoConfig c = gripper_config(name, node);
    c.startup_pause = [this] {
      if (during_startup) during_startup();
      drives.step(now);
      io_node->step(now);
      now += ms;
      bus_port.now = now;
      return now;
    };
    auto io = std::make_unique<CanopenIo>(who, TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    io->state_table().finalize();
    return io;
  }
  // One period as a canopen_bus runs it: the bus task's route phase, its clients, its send
  // phase (their RPDOs, then SYNC), then the nodes (their TPDOs for the next).
  void cycle(std::initializer_list<Task*> clients, int n = 1) {
    for (int i = 0; i < n; ++i) {
      bus_port.now = now;
      task->route(now);
      for (Task* a : clients) detail::Access::step(*a, now);
      task->send(now);
      if (io_node) io_node->step(now);
      drives.step(now);
      now += ms;
      can::Received r[64];
      for (std::size_t k; (k = spy.receive(r)) > 0;)
        for (std::size_t j = 0; j < k && keep; ++j) seen.push_back(r[j].frame);
    }
  }

  std::function<void()> during_startup;  // called at each pause of a client's start-up
  std::vector<can::Frame> seen;          // every frame on the bus during cycle() (unless not kept)
  bool keep = true;
  std::unique_ptr<FakeIoNode> fake_io;
  FakeIoNode* io_node = nullptr;
  const std::string name = "shared-test-bus";
  RingNetwork network;
  RingPort& bus_port;
  RingPort& spy;
  Drives drives{network, {}};
  std::shared_ptr<BusTask> task;
  TimeNs now = 0;
};

// What a client sends a device's CRTK command through: its mailbox, run at the next cycle.
struct Client {
  explicit Client(Task& t) {
    detail::Access::add_inbound(t, &mailbox);
    servo_jp = mailbox.add_target(execute_of(*t.provided("gripper")->find_command("servo_jp")));
    state = mailbox.add_target(execute_of(*t.provided("gripper")->find_command("state_command")));
  }
  void command(StateCommand c) { (void)mailbox.push(state, &c, sizeof c); }
  void jp(double q) {
    JointState js;
    js.size = 1;
    js.position[0] = q;
    (void)mailbox.push(servo_jp, &js, sizeof js);
  }
  detail::Mailbox mailbox{"test client", 16, sizeof(JointState)};
  std::uint32_t servo_jp = 0, state = 0;
};

}  // namespace saw::canopen::test
