// canopen_io (a generic CiA 401 I/O node: a gripper's jaw) as a client of a shared bus task,
// against saw-can-sim's simulated I/O node (SimIoNode, written from CiA 301/401) on an in-memory
// bus, stepped one 1 ms cycle at a time: what the hardware puts out is the node's analog output
// 0x6411:01 as the node took it from its RPDO on a SYNC.
#pragma once

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>

#include "../canopen/shared_rig.hpp"
#include "conformance.hpp"
#include "saw/canopen/sim/sim_io_node.hpp"

namespace saw::conformance {

class CanopenIoRig : public Rig {
 public:
  static constexpr std::uint8_t node = 10;
  // The jaw's SI value is count × 1e-5 m: its safe value 0.02 m is count 2000, not CiA 401's
  // default error value (0): the node puts it out by itself when its consumer fires only because
  // the component configured its error value (0x6443:01, 0x6444:01).
  static constexpr double safe_value = 0.02;
  static constexpr std::int16_t safe_count = 2000;

  CanopenIoRig() : bus_port_(network_.attach("bus task")), node_port_(network_.attach("io node")) {
    canopen::BusTaskConfig k;
    k.heartbeat_period = 10 * canopen::test::ms;
    k.heartbeat_timeout = 50 * canopen::test::ms;  // the node's consumer time (0x1016:01)
    task_ = std::make_shared<canopen::BusTask>(std::make_unique<canopen::test::Borrowed>(bus_port_), k);
    canopen::publish_bus_task(bus_name_, task_);
    canopen::sim::SimIoNodeConfig n;
    n.node = node;
    node_ = std::make_unique<canopen::sim::SimIoNode>(n, node_port_);
    canopen::CanopenIoConfig c = canopen::test::gripper_config(bus_name_, node);
    c.contract.start_enabled = false;
    c.channels[0].offset = 0;
    c.channels[0].safe = safe_value;
    c.startup_pause = [this] {
      if (powered_) step_node();
      now_ += canopen::test::ms;
      bus_port_.now = now_;
      return now_;
    };
    io_ = std::make_unique<canopen::CanopenIo>("gripper",
                                               TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    wire(*io_, {"servo_jp", "state_command"});
  }
  ~CanopenIoRig() override {
    io_.reset();
    canopen::withdraw_bus_task(bus_name_);
  }

  Device& device() override { return *io_; }
  canopen::CanopenIo& io() { return *io_; }
  canopen::sim::SimIoNode& sim() { return *node_; }

  // One period: the bus task (frames routed, last cycle's RPDOs, SYNC), the component, the node.
  void cycle(int n) override {
    for (int i = 0; i < n; ++i, now_ += canopen::test::ms) {
      bus_port_.now = now_;
      task_->cycle(now_);
      detail::Access::step(*io_, now_);
      step_node();
    }
  }
  // Periods in which the component does not run (a starved task) while its bus task's SYNC and
  // heartbeat go on: only its RPDOs stop.
  void starve(int n) {
    for (int i = 0; i < n; ++i, now_ += canopen::test::ms) {
      bus_port_.now = now_;
      task_->cycle(now_);
      step_node();
    }
  }
  // The jaw: good 0.05 m (3000 counts from safe), other 0.025 m (500), over limit twice its 0.08 m.
  void send(Command c) override {
    JointState js;
    js.size = 1;
    js.position[0] = value_of(c, 0.05, io_->contract().joints[0].max);
    write("servo_jp", js);
  }
  // How far the node's output is from the safe value, in counts.
  double output() const override { return std::abs(int{node_->output()} - safe_count); }
  // A node without power puts nothing out (fail_start): safe as it is.
  bool safe() const override { return !powered_ || node_->output() == safe_count; }
  // The node falls silent (its heartbeat stops; it still takes PDOs and SYNC).
  bool break_hardware() override {
    canopen::sim::Fault f;
    f.kind = canopen::sim::FaultKind::heartbeat_loss;
    node_->inject(f);
    return true;
  }
  // The node is not powered: no boot-up, no SDO answer.
  bool fail_start() override {
    powered_ = false;
    return true;
  }
  // The node takes the last frames the component sent as it stopped (no bus task cycles then).
  void settle_after_stop() override { step_node(); }
  // No SYNC, RPDO or master heartbeat from now on: the node alone.
  bool kill_controller(TimeNs alone) override {
    for (TimeNs t = 0; t < alone; t += canopen::test::ms, now_ += canopen::test::ms) step_node();
    return true;
  }

 private:
  void step_node() {
    node_port_.now = now_;
    node_->step(now_);
  }

  const std::string bus_name_ = "conformance-io-bus";
  canopen::test::RingNetwork network_;
  canopen::test::RingPort& bus_port_;
  canopen::test::RingPort& node_port_;
  std::shared_ptr<canopen::BusTask> task_;
  std::unique_ptr<canopen::sim::SimIoNode> node_;
  std::unique_ptr<canopen::CanopenIo> io_;
  bool powered_ = true;
  TimeNs now_ = 0;
};

}  // namespace saw::conformance
