// The simulated drive as a CiA 301 slave, against the protocol library's master pieces: boot-up,
// NMT and its resets, SDO (gated on the NMT state), heartbeat, PDO remapping by SDO and the
// exchange on SYNC, nothing but NMT and heartbeats outside operational, every frame checked.
#include <gtest/gtest.h>

#include <string>

#include "saw/canopen/cia402.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sync.hpp"
#include "sim_bench.hpp"

namespace saw::canopen::sim {
namespace {

using namespace testing;
namespace obj = cia402::object;

TEST(SimDriveProtocol, BootsPreOperationalWithOneBootUpMessage) {
  Bench b;
  EXPECT_EQ(b.drive.nmt_state(), NmtState::initialising) << "nothing happens before the first step";
  b.tick();
  EXPECT_EQ(b.drive.nmt_state(), NmtState::pre_operational);
  ASSERT_EQ(b.seen.size(), 1u);
  const auto hb = parse_heartbeat(b.seen[0].frame);
  ASSERT_TRUE(hb);
  EXPECT_EQ(hb->node, b.node);
  EXPECT_TRUE(hb->boot_up());
  b.run_for(500 * ms);
  EXPECT_EQ(b.seen.size(), 1u) << "0x1017 is 0 in sim_drive.eds: no heartbeat, no PDO, no EMCY";
}

TEST(SimDriveProtocol, SdoReadsIdentityExpeditedAndTheDeviceNameSegmented) {
  Bench b;
  b.tick();
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1000, 0}, DataType::unsigned32), 0x00020192u);
  EXPECT_EQ(b.upload_value<std::uint8_t>({0x1018, 0}, DataType::unsigned8), 4u);
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1018, 1}, DataType::unsigned32), 0x000005A7u);
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1018, 2}, DataType::unsigned32), 0x00402100u);
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1018, 4}, DataType::unsigned32), 0x53490000u + b.node)
      << "$NODEID in the EDS resolved";
  std::vector<std::uint8_t> name;
  ASSERT_EQ(b.upload({0x1008, 0}, &name).status, SdoStatus::done);
  EXPECT_EQ(std::string(name.begin(), name.end()), "sawrt simulated CiA 402 drive");
  EXPECT_EQ(b.upload({0x1234, 0}).abort, SdoAbort::no_object);
  EXPECT_EQ(b.download({0x1000, 0}, DataType::unsigned32, 1u).abort, SdoAbort::read_only);
}

TEST(SimDriveProtocol, SdoIsServedInPreOperationalAndOperationalOnly) {
  Bench b;
  b.tick();
  b.nmt(NmtCommand::start);
  b.tick();
  EXPECT_EQ(b.drive.nmt_state(), NmtState::operational);
  EXPECT_EQ(b.upload_value<std::uint16_t>(obj::statusword, DataType::unsigned16) & 0x4F, 0x40)
      << "switch on disabled";
  b.nmt(NmtCommand::stop);
  b.tick();
  EXPECT_EQ(b.drive.nmt_state(), NmtState::stopped);
  const SdoResult r = b.upload({0x1000, 0});
  EXPECT_EQ(r.status, SdoStatus::failed);
  EXPECT_EQ(r.abort, SdoAbort::timeout) << "stopped: no SDO answer";
  EXPECT_FALSE(r.remote);
  b.nmt(NmtCommand::enter_pre_operational);
  b.tick();
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1000, 0}, DataType::unsigned32), 0x00020192u);
}

TEST(SimDriveProtocol, NmtResetsRestoreTheirAreaAndBootAgain) {
  Bench b;
  b.tick();
  b.write(obj::following_error_window, DataType::unsigned32, 77u);
  b.write({0x1017, 0}, DataType::unsigned16, std::uint16_t{20});
  b.nmt(NmtCommand::start);
  b.tick();
  b.nmt(NmtCommand::reset_communication);
  b.tick();
  EXPECT_EQ(b.drive.nmt_state(), NmtState::pre_operational);
  EXPECT_EQ(b.upload_value<std::uint16_t>({0x1017, 0}, DataType::unsigned16), 0u)
      << "communication area reset";
  EXPECT_EQ(b.upload_value<std::uint32_t>(obj::following_error_window, DataType::unsigned32), 77u)
      << "the application's objects are not";
  b.nmt(NmtCommand::reset_node);
  b.tick();
  EXPECT_EQ(b.upload_value<std::uint32_t>(obj::following_error_window, DataType::unsigned32), 2000u)
      << "reset node restores everything";
  std::size_t boot_ups = 0;
  for (const auto& s : b.seen)
    if (auto hb = parse_heartbeat(s.frame); hb && hb->boot_up()) ++boot_ups;
  EXPECT_EQ(boot_ups, 3u) << "power-on and each reset";
  b.send(nmt_frame(NmtCommand::start, static_cast<std::uint8_t>(b.node + 1)));
  b.tick();
  EXPECT_EQ(b.drive.nmt_state(), NmtState::pre_operational) << "another node's command";
  b.send(nmt_frame(NmtCommand::start, 0));
  b.tick();
  EXPECT_EQ(b.drive.nmt_state(), NmtState::operational) << "node 0: every node";
}

TEST(SimDriveProtocol, HeartbeatFollows0x1017AndCarriesTheState) {
  Bench b;
  b.tick();
  b.write({0x1017, 0}, DataType::unsigned16, std::uint16_t{10});
  b.run_for(100 * ms);
  b.nmt(NmtCommand::start);
  b.run_for(100 * ms);
  std::vector<std::pair<TimeNs, NmtState>> beats;
  for (const auto& s : b.seen)
    if (auto hb = parse_heartbeat(s.frame); hb && !hb->boot_up()) beats.emplace_back(s.time, hb->state);
  ASSERT_GE(beats.size(), 18u);
  EXPECT_EQ(beats.front().second, NmtState::pre_operational);
  EXPECT_EQ(beats.back().second, NmtState::operational);
  for (std::size_t i = 1; i < beats.size(); ++i) {
    EXPECT_GE(beats[i].first - beats[i - 1].first, 10 * ms - Bench::period);
    EXPECT_LE(beats[i].first - beats[i - 1].first, 10 * ms + Bench::period);
  }
  const auto& appeared = b.events.front();
  EXPECT_EQ(appeared.kind, HeartbeatEvent::Kind::appeared);
}

PdoMapping tpdo1(std::uint8_t node) {
  PdoMapping m;
  m.kind = PdoKind::tpdo;
  m.number = 1;
  m.cob_id = default_pdo_cob_id(PdoKind::tpdo, 1, node);
  m.map(obj::statusword, DataType::unsigned16)
      .map(obj::velocity_actual_value, DataType::integer32)
      .map(obj::modes_of_operation_display, DataType::integer8);
  return m;
}

PdoMapping rpdo1(std::uint8_t node) {
  PdoMapping m;
  m.kind = PdoKind::rpdo;
  m.number = 1;
  m.cob_id = default_pdo_cob_id(PdoKind::rpdo, 1, node);
  m.map(obj::controlword, DataType::unsigned16)
      .map(obj::target_torque, DataType::integer16)
      .map(obj::modes_of_operation, DataType::integer8);
  return m;
}

void configure(Bench& b, const PdoMapping& m) {
  for (const SdoWrite& w : configuration_writes(m)) {
    const SdoResult r = b.download(w.address, w.type, w.value);
    ASSERT_EQ(r.status, SdoStatus::done) << to_string(w.address) << ": " << to_string(r.abort);
  }
}

TEST(SimDriveProtocol, PdosRemappedBySdoAreExchangedOnSync) {
  Bench b;
  b.tick();
  const PdoMapping tx = tpdo1(b.node), rx = rpdo1(b.node);
  configure(b, tx);
  configure(b, rx);
  EXPECT_EQ(b.upload_value<std::uint8_t>({0x1A00, 0}, DataType::unsigned8), 3u);
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1600, 2}, DataType::unsigned32), 0x60710010u);
  b.nmt(NmtCommand::start);
  b.tick();

  PdoPacker command(rx);
  PdoUnpacker status(tx);
  (void)command.set(0, cia402::controlword::shutdown_command);
  (void)command.set(1, std::int16_t{0});
  (void)command.set(2, static_cast<std::int8_t>(cia402::cst));
  int syncs = 0;
  b.each_tick = [&] {
    if (b.now % ms != 0) return;
    b.send(sync_frame());
    b.send(command.frame());
    ++syncs;
  };
  b.run_for(20 * ms);
  b.each_tick = nullptr;
  int tpdos = 0;
  for (const auto& s : b.seen) {
    if (s.frame.can_id() != tx.cob_id) continue;
    ++tpdos;
    EXPECT_EQ(s.frame.len, 7u) << "the new mapping's length";
    EXPECT_EQ(status.receive(s.frame), PdoReceive::ok);
  }
  EXPECT_EQ(tpdos, syncs) << "transmission type 1: one TPDO per SYNC";
  std::uint16_t sw = 0;
  std::int8_t mode = 0;
  ASSERT_EQ(status.get(0, sw), Codec::ok);
  ASSERT_EQ(status.get(2, mode), Codec::ok);
  EXPECT_EQ(cia402::decode_state(sw), cia402::State::ready_to_switch_on) << "the RPDO's controlword acted";
  EXPECT_EQ(mode, static_cast<std::int8_t>(cia402::cst)) << "the RPDO's mode, shown in 0x6061";
  EXPECT_EQ(b.count(default_pdo_cob_id(PdoKind::tpdo, 2, b.node)), static_cast<std::size_t>(syncs))
      << "TPDO2 as sim_drive.eds configures it";
}

TEST(SimDriveProtocol, PdoConfigurationWritesAreCheckedAsCiA301Says) {
  Bench b;
  b.tick();
  EXPECT_EQ(b.download({0x1A00, 1}, DataType::unsigned32, 0x60640020u).abort, SdoAbort::unsupported_access)
      << "the mapping of a valid PDO";
  EXPECT_EQ(b.download({0x1800, 1}, DataType::unsigned32, 0x190u + b.node).abort, SdoAbort::invalid_value)
      << "a valid PDO's identifier cannot change";
  b.write({0x1800, 1}, DataType::unsigned32, 0x80000180u + b.node);
  EXPECT_EQ(b.download({0x1A00, 1}, DataType::unsigned32, 0x60640020u).abort, SdoAbort::unsupported_access)
      << "entries only while sub-index 0 is 0";
  b.write({0x1A00, 0}, DataType::unsigned8, std::uint8_t{0});
  EXPECT_EQ(b.download({0x1A00, 1}, DataType::unsigned32, 0x10000020u).abort, SdoAbort::not_mappable)
      << "0x1000 is not PDO-mappable";
  EXPECT_EQ(b.download({0x1A00, 1}, DataType::unsigned32, 0x60640010u).abort, SdoAbort::not_mappable)
      << "16 bits of an INTEGER32";
  EXPECT_EQ(b.download({0x1A00, 1}, DataType::unsigned32, 0x60FE0020u).abort, SdoAbort::no_object);
  EXPECT_EQ(b.download({0x1600, 1}, DataType::unsigned32, 0x60410010u).abort, SdoAbort::unsupported_access)
      << "RPDO1 is valid";
  for (std::uint8_t i = 1; i <= 3; ++i) b.write({0x1A00, i}, DataType::unsigned32, 0x60640020u);
  EXPECT_EQ(b.download({0x1A00, 0}, DataType::unsigned8, std::uint8_t{3}).abort, SdoAbort::pdo_too_long)
      << "96 bits";
  b.write({0x1A00, 0}, DataType::unsigned8, std::uint8_t{2});
  EXPECT_EQ(b.download({0x1800, 2}, DataType::unsigned8, std::uint8_t{252}).abort, SdoAbort::invalid_value)
      << "RTR-only transmission is not simulated";
  EXPECT_EQ(b.download({0x1800, 1}, DataType::unsigned32, 0x701u).abort, SdoAbort::invalid_value)
      << "a heartbeat identifier";
  b.write({0x1800, 1}, DataType::unsigned32, 0x40000000u | (0x180u + b.node));  // bit 30 (no RTR) is fine
  b.nmt(NmtCommand::start);
  b.tick();
  b.send(sync_frame());
  b.tick();
  ASSERT_EQ(b.count(0x180u + b.node), 1u);
  for (const auto& s : b.seen)
    if (s.frame.can_id() == 0x180u + b.node) {
      EXPECT_EQ(s.frame.len, 8u) << "two INTEGER32";
    }
}

TEST(SimDriveProtocol, NoPdoOutsideOperational) {
  Bench b;
  b.tick();
  const std::uint32_t rpdo = 0x200u + b.node;
  const std::uint8_t shutdown[6] = {0x06, 0, 0, 0, 0, 0};
  b.each_tick = [&] {
    if (b.now % ms != 0) return;
    b.send(sync_frame());
    b.send(can::classic(rpdo, shutdown));
  };
  b.run_for(20 * ms);
  EXPECT_EQ(b.count(0x180u + b.node) + b.count(0x280u + b.node), 0u) << "pre-operational";
  EXPECT_EQ(b.drive.drive_state(), cia402::State::switch_on_disabled) << "the RPDO was not processed";
  b.nmt(NmtCommand::start);
  b.run_for(5 * ms);
  EXPECT_GT(b.count(0x180u + b.node), 0u);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::ready_to_switch_on);
  b.nmt(NmtCommand::stop);
  b.tick();
  const std::size_t before = b.seen.size();
  b.run_for(20 * ms);
  EXPECT_EQ(b.seen.size(), before) << "stopped: nothing (no heartbeat configured)";
  EXPECT_EQ(b.drive.counters().rpdos, 5u);
}

TEST(SimDriveProtocol, EveryFrameIsCheckedBeforeUse) {
  Bench b;
  b.tick();
  can::Frame fd = can::classic(0x600u + b.node, std::array<std::uint8_t, 8>{0x40, 0x00, 0x10, 0, 0, 0, 0, 0});
  fd.flags = CANFD_FDF;
  can::Frame extended = can::classic(0x600u + b.node, std::array<std::uint8_t, 8>{0x40, 0x00, 0x10});
  extended.id |= CAN_EFF_FLAG;
  can::Frame remote = can::classic(0x600u + b.node, {});
  remote.id |= CAN_RTR_FLAG;
  remote.len = 8;
  for (const auto& f : {fd, extended, remote}) b.send(f);
  b.send(can::classic(0x000, std::array<std::uint8_t, 3>{0x01, b.node, 0}));  // NMT with 3 bytes
  b.send(can::classic(0x000, std::array<std::uint8_t, 2>{0x55, b.node}));     // no such command
  b.run_for(5 * ms);
  EXPECT_EQ(b.drive.counters().not_canopen, 3u);
  EXPECT_EQ(b.drive.counters().sdo_requests, 0u);
  EXPECT_EQ(b.drive.nmt_state(), NmtState::pre_operational);
  EXPECT_EQ(b.seen.size(), 1u) << "only the boot-up message";
}

TEST(SimDriveProtocol, AnRpdoOfTheWrongLengthIsNotProcessedAndRaisesEmcy8210) {
  Bench b;
  b.tick();
  b.nmt(NmtCommand::start);
  b.tick();
  b.send(can::classic(0x200u + b.node, std::array<std::uint8_t, 4>{0x06, 0, 0, 0}));
  b.send(sync_frame());
  b.run_for(2 * ms);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::switch_on_disabled);
  ASSERT_EQ(b.emcys().size(), 1u);
  EXPECT_EQ(b.emcys()[0].code, 0x8210);
  EXPECT_NE(b.emcys()[0].error_register & error_register::communication, 0);
  b.send(can::classic(0x200u + b.node, std::array<std::uint8_t, 6>{0x06, 0, 0, 0, 0, 0}));
  b.send(sync_frame());
  b.run_for(2 * ms);
  ASSERT_EQ(b.emcys().size(), 2u);
  EXPECT_TRUE(b.emcys()[1].is_reset()) << "a good RPDO ends the condition";
  EXPECT_EQ(b.drive.drive_state(), cia402::State::ready_to_switch_on);
}

TEST(SimDriveProtocol, RunsOnAVendorEdsCompletedWithWhatItNeeds) {
  SimDriveConfig c = Bench::default_config();
  c.eds = SAW_CANOPEN_TEST_DATA "/drive.eds";
  Bench b(c);
  b.tick();
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1018, 1}, DataType::unsigned32), 0x000005A7u);
  EXPECT_EQ(b.upload_value<std::uint8_t>({0x2F00, 0}, DataType::unsigned8), 5u)
      << "the injection record, added";
  EXPECT_EQ(b.download(obj::modes_of_operation, DataType::integer8, std::int8_t{1}).abort,
            SdoAbort::invalid_value)
      << "profile position is not a mode this drive has";
  b.write(obj::modes_of_operation, DataType::integer8, std::int8_t{9});
  b.tick();
  EXPECT_EQ(b.upload_value<std::int8_t>(obj::modes_of_operation_display, DataType::integer8), 9);
}

}  // namespace
}  // namespace saw::canopen::sim
