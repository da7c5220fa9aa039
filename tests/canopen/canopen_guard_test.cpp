// The CANopen RT paths (PDO pack and unpack, SYNC, the CiA 402 controller and drive, heartbeat,
// EMCY, NMT, an SDO transfer in flight, unit conversions) allocate nothing, lock nothing and
// write no stdio in a 1 kHz cycle, checked by the RT guard from the first cycle.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "guard_support.hpp"
#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/cia402_drive.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sdo_server.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/canopen/units.hpp"
#include "saw/rt_context.hpp"

namespace {

using namespace saw::canopen;
using saw::TimeNs;
using saw::can::Frame;

constexpr std::uint8_t node = 2;
constexpr TimeNs ms = 1'000'000;

PdoMapping rpdo() {
  PdoMapping m;
  m.kind = PdoKind::rpdo;
  m.cob_id = default_pdo_cob_id(PdoKind::rpdo, 1, node);
  m.map(cia402::object::controlword, DataType::unsigned16)
      .map(cia402::object::target_position, DataType::integer32)
      .map(cia402::object::target_torque, DataType::integer16);
  return m;
}

PdoMapping tpdo() {
  PdoMapping m;
  m.kind = PdoKind::tpdo;
  m.cob_id = default_pdo_cob_id(PdoKind::tpdo, 1, node);
  m.map(cia402::object::statusword, DataType::unsigned16)
      .map(cia402::object::position_actual_value, DataType::integer32)
      .map(cia402::object::torque_actual_value, DataType::integer16);
  return m;
}

TEST(RtGuard, CanopenMasterAndSimulatedDriveCyclesAreRtClean) {
  saw::testing::GuardWindow window;

  // Set-up (not RT): both ends of one drive's traffic.
  const DriveUnits units = DriveUnits::rotary(4096, 100, 0.318);
  SyncProducer sync(1 * ms);
  PdoPacker master_rpdo(rpdo());
  PdoUnpacker master_tpdo(tpdo());
  cia402::Controller controller;
  HeartbeatConsumer heartbeats;
  heartbeats.watch(node, 50 * ms);
  SdoClient sdo(SdoClientConfig{SdoChannel::of_node(node)});

  LocalDictionary dictionary;
  dictionary.add_value(cia402::object::statusword, "Statusword", DataType::unsigned16, Access::ro, 0u);
  dictionary.add_value(cia402::object::target_position, "Target position", DataType::integer32, Access::rww,
                       0);
  Entry name{"Manufacturer device name", DataType::visible_string, Access::const_, {}, {}, {}, 64, false};
  const char* text = "sawrt simulated CiA 402 drive";
  name.value.assign(text, text + std::strlen(text));
  dictionary.add({0x1008, 0}, name);
  SdoServer server(SdoServerConfig{SdoChannel::of_node(node)}, dictionary);
  cia402::Drive drive;
  PdoUnpacker drive_rpdo(rpdo());
  PdoPacker drive_tpdo(tpdo());
  NmtNode nmt(node);
  nmt.boot();
  HeartbeatProducer heartbeat(node, 10 * ms);
  heartbeat.start(0);
  EmcyProducer emcy(node, 1 * ms);

  constexpr int cycles = 3000;
  int reached = 0, faults = 0, transfers = 0, events = 0;
  std::int32_t position = 0;
  bool fault = false;
  {
    saw::RtContextScope rt;
    for (int i = 0; i < cycles; ++i) {
      saw::RtCycleScope cycle("canopen");
      const TimeNs now = i * ms;
      // --- master ---
      if (auto f = sync.poll(now)) (void)parse_sync(*f);
      if (master_tpdo.receive(drive_tpdo.frame()) == PdoReceive::ok) {
        std::uint16_t sw = 0;
        std::int32_t counts = 0;
        std::int16_t torque = 0;
        (void)master_tpdo.get(0, sw);
        (void)master_tpdo.get(1, counts);
        (void)master_tpdo.get(2, torque);
        const double q = units.counts_to_position(counts) + units.per_mille_to_torque(torque);
        if (i == 10) controller.set_target(cia402::Target::operation_enabled, now);
        if (i == 2000) controller.request_fault_reset(now);
        const auto out = controller.update(sw, now);
        reached += out.progress == cia402::Progress::reached;
        faults += out.progress == cia402::Progress::fault;
        std::int32_t target = 0;
        std::int16_t tau = 0;
        (void)units.position_to_counts(q + 0.001 * std::sin(i * 0.01), target);
        (void)units.torque_to_per_mille(0.01, tau);
        (void)master_rpdo.set(0, out.controlword);
        (void)master_rpdo.set(1, target);
        (void)master_rpdo.set(2, tau);
      }
      // An SDO upload every 100 cycles, segmented every other time.
      if (i % 100 == 0)
        (void)sdo.upload(i % 200 == 0 ? ObjectAddress{0x1008, 0} : cia402::object::statusword, now);
      if (auto request = sdo.poll(now)) server.on_frame(*request, now);
      if (auto response = server.poll(now)) {
        sdo.on_frame(*response, now);
        transfers += sdo.result().status == SdoStatus::done;
      }
      // --- drive ---
      if (drive_rpdo.receive(master_rpdo.frame()) == PdoReceive::ok) {
        std::uint16_t cw = 0;
        (void)drive_rpdo.get(0, cw);
        (void)drive_rpdo.get(1, position);
        fault = i >= 1500 && i < 1800;
        if (i == 1500) (void)emcy.raise(0x2310, error_register::current | error_register::generic);
        if (i == 1800) (void)emcy.clear();
        drive.update({cw, fault, true, true});
        (void)dictionary.set(cia402::object::statusword, drive.statusword());
      }
      (void)drive_tpdo.set(0, drive.statusword());
      (void)drive_tpdo.set(1, position);
      (void)drive_tpdo.set(2, std::int16_t{12});
      (void)nmt.on_frame(nmt_frame(NmtCommand::start, node));
      if (auto f = nmt.poll()) heartbeats.on_frame(*f, now);
      if (auto f = heartbeat.poll(now, nmt.state())) heartbeats.on_frame(*f, now);
      if (auto f = emcy.poll(now)) (void)parse_emcy(*f);
      while (heartbeats.poll(now)) ++events;
    }
  }
  const auto counts = window.counts();
  EXPECT_GT(reached, 1000) << "the drive was enabled";
  EXPECT_GT(faults, 100) << "and went through a fault";
  EXPECT_EQ(drive.state(), cia402::State::operation_enabled) << "and was reset and enabled again";
  EXPECT_GE(transfers, 29) << "SDO transfers completed in the cycle";
  EXPECT_GT(events, 0);
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
