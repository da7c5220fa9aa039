// The simulated drive's cycle allocates, locks and prints nothing once configured: SimDrive::step
// with SDO (expedited and segmented), SYNC, RPDOs and TPDOs, heartbeat, the CiA 402 walk, CSP
// motion, an injected fault with its EMCY and the fault reset, checked by the RT guard; and the
// simulated I/O node's (SimIoNode::step): SDO, SYNC, its output and input, EMCYs, its consumer.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "guard_support.hpp"
#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sim/sim_drive.hpp"
#include "saw/canopen/sim/sim_io_node.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/rt_context.hpp"

namespace saw::canopen::sim {
namespace {

constexpr TimeNs us = 1'000, ms = 1'000'000;
constexpr std::uint8_t node = 6;

// Two ports in fixed memory (the tests' deque-based bus would allocate in the window).
class RingBus final : public can::Bus {
 public:
  void connect(RingBus& peer) noexcept { peer_ = &peer; }
  std::size_t receive(std::span<can::Received> out) noexcept override {
    std::size_t n = 0;
    for (; n < out.size() && tail_ != head_; ++n) out[n] = ring_[tail_++ % ring_.size()];
    return n;
  }
  std::size_t send(std::span<const can::Frame> frames) noexcept override {
    for (const auto& f : frames) peer_->ring_[peer_->head_++ % ring_.size()] = {f, 0};
    return frames.size();
  }
  can::BusState state() const noexcept override { return can::BusState::error_active; }
  can::BusCounters counters() const noexcept override { return {}; }
  const std::string& name() const noexcept override { return name_; }

 private:
  std::array<can::Received, 256> ring_{};
  std::size_t head_ = 0, tail_ = 0;
  RingBus* peer_ = nullptr;
  std::string name_ = "ring";
};

PdoMapping mapping(PdoKind kind) {
  PdoMapping m;
  m.kind = kind;
  m.cob_id = default_pdo_cob_id(kind, 1, node);
  if (kind == PdoKind::rpdo) {
    m.map(cia402::object::controlword, DataType::unsigned16)
        .map(cia402::object::target_position, DataType::integer32);
  } else {
    m.map(cia402::object::statusword, DataType::unsigned16)
        .map(cia402::object::position_actual_value, DataType::integer32)
        .map(cia402::object::torque_actual_value, DataType::integer16);
  }
  return m;
}

TEST(RtGuard, SimulatedDriveCycleIsRtClean) {
  saw::testing::GuardWindow window;
  RingBus master_bus, drive_bus;
  master_bus.connect(drive_bus);
  drive_bus.connect(master_bus);
  SimDriveConfig config;
  config.node = node;
  config.heartbeat_ms = 10;
  SimDrive drive(config, drive_bus);
  SdoClient sdo(SdoClientConfig{SdoChannel::of_node(node)});
  PdoPacker rpdo(mapping(PdoKind::rpdo));
  PdoUnpacker tpdo(mapping(PdoKind::tpdo));
  cia402::Controller controller;
  std::uint16_t statusword = 0;
  std::int32_t position = 0;
  int transfers = 0, reached = 0, faults = 0;

  constexpr int cycles = 12'000;  // 3 s of 250 µs drive steps, the master every 4th
  {
    saw::RtContextScope rt;
    for (int i = 0; i < cycles; ++i) {
      saw::RtCycleScope cycle("sim-drive");
      const TimeNs now = i * 250 * us;
      if (i == 4) (void)master_bus.send(std::array{nmt_frame(NmtCommand::start, node)});
      if (i % 4 == 0) {
        can::Received rx[64];
        for (std::size_t n; (n = master_bus.receive(rx)) > 0;)
          for (std::size_t k = 0; k < n; ++k) {
            sdo.on_frame(rx[k].frame, now);
            if (tpdo.receive(rx[k].frame) == PdoReceive::ok) {
              (void)tpdo.get(0, statusword);
              (void)tpdo.get(1, position);
            }
          }
        transfers += sdo.result().status == SdoStatus::done;
        if (i % 400 == 0)
          (void)sdo.upload(i % 800 == 0 ? ObjectAddress{0x1008, 0} : cia402::object::statusword, now);
        if (i == 40) controller.set_target(cia402::Target::operation_enabled, now);
        if (i == 8000) controller.request_fault_reset(now);
        const auto out = controller.update(statusword, now);
        reached += out.progress == cia402::Progress::reached;
        faults += out.progress == cia402::Progress::fault;
        (void)rpdo.set(0, out.controlword);
        (void)rpdo.set(1, static_cast<std::int32_t>(std::lround(2000 * std::sin(i * 1e-3))));
        if (auto f = sdo.poll(now)) (void)master_bus.send(std::span(&*f, 1));
        (void)master_bus.send(std::array{sync_frame(), rpdo.frame()});
      }
      if (i == 6000) drive.inject({FaultKind::over_current});
      drive.step(now);
    }
  }
  const auto counts = window.counts();
  EXPECT_GT(reached, 1000) << "enabled";
  EXPECT_GT(faults, 10) << "then in fault";
  EXPECT_EQ(drive.drive_state(), cia402::State::operation_enabled) << "and enabled again after the reset";
  EXPECT_GE(transfers, 20) << "SDO transfers, expedited and segmented";
  EXPECT_GT(drive.counters().heartbeats, 250u);
  EXPECT_EQ(drive.counters().emcys, 2u) << "0x2310 and its reset";
  EXPECT_NE(position, 0) << "CSP moved the motor";
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

TEST(RtGuard, SimulatedIoNodeCycleIsRtClean) {
  saw::testing::GuardWindow window;
  constexpr std::uint8_t io = 10;
  RingBus master_bus, node_bus;
  master_bus.connect(node_bus);
  node_bus.connect(master_bus);
  SimIoNodeConfig config;
  config.node = io;
  config.heartbeat_ms = 10;
  SimIoNode gripper(config, node_bus);
  SdoClient sdo(SdoClientConfig{SdoChannel::of_node(io)});
  PdoMapping out_map, in_map;
  out_map.kind = PdoKind::rpdo;
  out_map.cob_id = default_pdo_cob_id(PdoKind::rpdo, 1, io);
  out_map.map({0x6411, 1}, DataType::integer16);
  in_map.kind = PdoKind::tpdo;
  in_map.cob_id = default_pdo_cob_id(PdoKind::tpdo, 1, io);
  in_map.map({0x6401, 1}, DataType::integer16);
  PdoPacker rpdo(out_map);
  PdoUnpacker tpdo(in_map);
  std::int16_t input = 0, most = 0;
  int emcy_2310 = 0, emcy_8130 = 0, written = 0;
  const std::uint8_t consumer[4] = {100, 0, 127, 0};  // node 127, 100 ms

  constexpr int cycles = 3000;  // 1 ms steps
  {
    saw::RtContextScope rt;
    for (int i = 0; i < cycles; ++i) {
      saw::RtCycleScope cycle("sim-io-node");
      const TimeNs now = i * ms;
      if (i == 5) (void)sdo.download({0x1016, 1}, consumer, now);
      if (i == 50) (void)master_bus.send(std::array{nmt_frame(NmtCommand::start, io)});
      can::Received rx[64];
      for (std::size_t n; (n = master_bus.receive(rx)) > 0;)
        for (std::size_t k = 0; k < n; ++k) {
          const can::Frame& f = rx[k].frame;
          sdo.on_frame(f, now);
          if (tpdo.receive(f) == PdoReceive::ok && tpdo.get(0, input) == Codec::ok)
            most = std::max(most, input);
          if (f.can_id() == 0x80u + io && f.len == 8) {
            emcy_2310 += f.data[0] == 0x10 && f.data[1] == 0x23;
            emcy_8130 += f.data[0] == 0x30 && f.data[1] == 0x81;
          }
        }
      written += i == 40 && sdo.result().status == SdoStatus::done;
      if (auto f = sdo.poll(now)) (void)master_bus.send(std::span(&*f, 1));
      (void)rpdo.set(0, std::int16_t{2000});
      if (i < 2000) (void)master_bus.send(std::array{rpdo.frame(), sync_frame()});
      if (i < 2000 && i % 10 == 0)
        (void)master_bus.send(std::array{heartbeat_frame(127, NmtState::operational)});
      if (i == 1000) gripper.inject({FaultKind::over_current});
      gripper.step(now);
    }
  }
  const auto counts = window.counts();
  EXPECT_EQ(written, 1) << "0x1016:01 by SDO";
  EXPECT_EQ(most, 2000) << "the input followed the output";
  EXPECT_EQ(emcy_2310, 1);
  EXPECT_EQ(emcy_8130, 1) << "the master's heartbeat stopped at 2 s: its consumer fired";
  EXPECT_EQ(gripper.output(), 0) << "CiA 401's error value";
  EXPECT_EQ(gripper.heartbeat_events(), 1u);
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
}  // namespace saw::canopen::sim
