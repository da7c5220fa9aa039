// The simulated drive's cycle allocates, locks and prints nothing once configured: SimDrive::step
// with SDO (expedited and segmented), SYNC, RPDOs and TPDOs, heartbeat, the CiA 402 walk, CSP
// motion, an injected fault with its EMCY and the fault reset, checked by the RT guard.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "guard_support.hpp"
#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sim/sim_drive.hpp"
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

}  // namespace
}  // namespace saw::canopen::sim
