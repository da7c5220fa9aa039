// The bus master against in-process drives: start-up writes, the CiA 402 walk to operation
// enabled, CSP following, the order of a cycle's frames, heartbeat and EMCY, runtime SDO.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "rig.hpp"
#include "saw/canopen/bus_master.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/sync.hpp"

namespace {

using namespace saw::canopen;
using namespace saw::canopen::test;
using saw::TimeNs;

struct MasterRig {
  explicit MasterRig(std::vector<AxisConfig> a, BusMasterConfig config = {})
      : axes(std::move(a)),
        port(network.attach("master")),
        drives(network, axes),
        master(port, config, axes) {}
  void start() { start_up(port, axes, drives, now); }
  // One master cycle, then the drives answer (their TPDOs are read by the next cycle).
  template <class Logic>
  void cycle(Logic logic) {
    port.now = now;
    master.receive(now);
    logic();
    master.transmit(now);
    drives.step(now);
    now += ms;
  }
  void cycle() {
    cycle([] {});
  }
  void enable_all() {
    for (std::size_t i = 0; i < master.size(); ++i)
      master.set_state_target(i, cia402::Target::operation_enabled, now);
  }

  RingNetwork network;
  std::vector<AxisConfig> axes;
  RingPort& port;
  Drives drives;
  BusMaster master;
  TimeNs now = 0;
};

TEST(CanopenStartup, TheDeploymentsOwnWritesComeBeforeTheMode) {
  AxisConfig axis = test_axis(3, cia402::csp);
  axis.writes = {{cia402::object::interpolation_time_period_value, DataType::unsigned8, 10},
                 {cia402::object::interpolation_time_period_index, DataType::integer8, 0xFD}};
  axis.master_timeout = 0;  // a drive not told to watch the master: no 0x1016 write
  axis.abort_connection = AbortConnection::none;
  const auto planned = startup_writes(axis);
  const auto abort_option = std::find_if(planned.begin(), planned.end(), [](const StartupWrite& w) {
    return w.write.address == cia402::object::abort_connection_option_code;
  });
  ASSERT_NE(abort_option, planned.end());
  EXPECT_TRUE(abort_option->optional) << "none: a drive without 0x6007 is fine";
  EXPECT_EQ(abort_option->write.value, 0u);
  ASSERT_GE(planned.size(), 4u);
  EXPECT_EQ(planned[planned.size() - 3].write.address, cia402::object::interpolation_time_period_value);
  EXPECT_EQ(planned[planned.size() - 2].write.address, cia402::object::interpolation_time_period_index);
  EXPECT_EQ(std::get<std::int64_t>(startup_value(planned[planned.size() - 2].write)), -3);
  EXPECT_EQ(planned.back().write.address, cia402::object::modes_of_operation);
  EXPECT_TRUE(std::none_of(planned.begin(), planned.end(), [](const StartupWrite& w) {
    return w.write.address == ObjectAddress{0x1016, 1};
  }));
}

TEST(CanopenStartup, WritesThePdosTheHeartbeatTimeAndTheMode) {
  const AxisConfig axis = test_axis(3, cia402::cst);
  const auto planned = startup_writes(axis);
  ASSERT_GT(planned.size(), 20u);
  // The PDO writes come first, then 0x1017, 0x1016:01 (the master's node and heartbeat time, so
  // that the drive notices a master that is gone), 0x6007 (what it then does) and 0x6060.
  EXPECT_EQ(planned[planned.size() - 4].write.address, (ObjectAddress{0x1017, 0}));
  EXPECT_EQ(planned[planned.size() - 4].write.value, 10u);
  EXPECT_EQ(planned[planned.size() - 3].write.address, (ObjectAddress{0x1016, 1}));
  EXPECT_EQ(planned[planned.size() - 3].write.value, (127u << 16) | 300u) << "node 127, 300 ms";
  EXPECT_EQ(planned[planned.size() - 3].write.type, DataType::unsigned32);
  EXPECT_EQ(planned[planned.size() - 2].write.address, cia402::object::abort_connection_option_code);
  EXPECT_EQ(planned[planned.size() - 2].write.value, 3u) << "quick stop";
  EXPECT_EQ(planned[planned.size() - 2].write.type, DataType::integer16);
  EXPECT_EQ(planned.back().write.address, cia402::object::modes_of_operation);
  EXPECT_EQ(planned.back().write.value, 10u) << "cyclic synchronous torque";
  EXPECT_EQ(planned[0].write.address, (ObjectAddress{0x1400, 1}));
  EXPECT_EQ(planned[0].write.value, 0x80000203u) << "RPDO1 made not valid, its identifier kept";

  MasterRig rig({axis});
  rig.network.record = true;
  rig.start();
  // NMT reset communication of node 3 alone (after the power-on boot-up), the writes, NMT start.
  const auto& log = rig.network.log;
  const auto nmt = [&](std::size_t from) {
    for (std::size_t i = from; i < log.size(); ++i)
      if (log[i].can_id() == cob::nmt) return i;
    return log.size();
  };
  const std::size_t reset = nmt(0), start = nmt(reset + 1);
  ASSERT_LT(start, log.size());
  EXPECT_EQ(log[reset].data[0], 0x82);
  EXPECT_EQ(log[reset].data[1], 3);
  EXPECT_EQ(log[start].data[0], 0x01);
  EXPECT_EQ(log[start].data[1], 3);
  std::size_t requests = 0;
  for (std::size_t i = reset; i < start; ++i) requests += log[i].can_id() == 0x603;
  EXPECT_EQ(requests, planned.size()) << "every write between the reset and the start, expedited";
  const auto& written = rig.drives[0].writes();
  ASSERT_EQ(written.size(), planned.size()) << "every planned write reached the drive";
  for (std::size_t i = 0; i < planned.size(); ++i) {
    EXPECT_EQ(written[i].address, planned[i].write.address) << i;
    EXPECT_EQ(written[i].value, planned[i].write.value) << i;
  }
  EXPECT_EQ(rig.drives[0].nmt_state(), NmtState::operational);
  EXPECT_EQ(rig.drives[0].mode(), cia402::cst);
}

TEST(CanopenStartup, AMissingDriveFailsNamingItsNode) {
  RingNetwork network;
  RingPort& port = network.attach("master");
  const std::vector<AxisConfig> axes{test_axis(1, cia402::csp), test_axis(2, cia402::csp, "elbow")};
  Drives drives(network, {axes[0]});  // node 2 is not there
  TimeNs now = 0;
  StartupConfig config;
  config.boot_timeout = 50 * ms;
  try {
    start_up(port, axes, drives, now, config);
    FAIL() << "start-up should fail";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("node 2 ('elbow'): no boot-up within 50 ms"), std::string::npos)
        << e.what();
  }
}

TEST(CanopenStartup, ADriveThatRefusesTheModeFailsWithTheAbortsName) {
  RingNetwork network;
  RingPort& port = network.attach("master");
  AxisConfig axis = test_axis(1, cia402::csp);
  Drives drives(network, {axis});
  (void)drives[0].dictionary().set(cia402::object::supported_drive_modes, 0u);
  drives[0].dictionary().on_write([](ObjectAddress a, std::span<const std::uint8_t>) {
    return a == cia402::object::modes_of_operation ? SdoAbort::invalid_value : SdoAbort::none;
  });
  TimeNs now = 0;
  try {
    start_up(port, {axis}, drives, now);
    FAIL() << "start-up should fail";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("0x6060:00 failed: invalid value for parameter"), std::string::npos)
        << e.what();
  }
}

TEST(CanopenMaster, WalksEveryDriveToOperationEnabled) {
  MasterRig rig({test_axis(1, cia402::csp), test_axis(2, cia402::csp), test_axis(3, cia402::csp)});
  rig.start();
  rig.enable_all();
  for (int i = 0; i < 20; ++i) rig.cycle();
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(rig.drives[i].state(), cia402::State::operation_enabled) << i;
    EXPECT_EQ(rig.master.feedback(i).state, cia402::State::operation_enabled) << i;
    EXPECT_EQ(rig.master.control(i).progress, cia402::Progress::reached) << i;
    EXPECT_TRUE(rig.master.feedback(i).valid);
  }
  EXPECT_EQ(rig.master.counters().syncs, 20u);
  EXPECT_EQ(rig.drives[0].syncs(), 20u);
}

TEST(CanopenMaster, CspPositionsAreFollowedAndReadBackInRadians) {
  MasterRig rig({test_axis(1, cia402::csp)});
  rig.start();
  rig.enable_all();
  for (int i = 0; i < 10; ++i) rig.cycle([&] { (void)rig.master.set_setpoint(0, 0.0); });
  double last_sent = 0;
  for (int i = 0; i < 200; ++i) {
    const double target = 0.5 * std::sin(i * 0.02);
    rig.cycle([&] {
      // What the drive reached is what was sent one SYNC before.
      EXPECT_NEAR(rig.master.feedback(0).position, last_sent, 2 * M_PI / 4096) << i;
      ASSERT_EQ(rig.master.set_setpoint(0, target), Codec::ok);
      last_sent = target;
    });
  }
  EXPECT_NEAR(rig.drives[0].target_position(), 0.5 * std::sin(199 * 0.02) * 4096 / (2 * M_PI), 1.0);
  EXPECT_NE(rig.master.feedback(0).velocity, 0.0);
}

TEST(CanopenMaster, ACycleSendsItsRpdosBeforeItsSync) {
  MasterRig rig({test_axis(1, cia402::csp), test_axis(2, cia402::csp)});
  rig.start();
  rig.network.record = true;
  rig.network.log.clear();
  rig.cycle();
  // Only the master sent in this cycle before the drives answered: RPDO 1, RPDO 2, SYNC.
  ASSERT_GE(rig.network.log.size(), 3u);
  EXPECT_EQ(rig.network.log[0].can_id(), 0x201u);
  EXPECT_EQ(rig.network.log[1].can_id(), 0x202u);
  EXPECT_EQ(rig.network.log[2].can_id(), cob::sync);
}

TEST(CanopenMaster, RefusedSetpointsAreNotPacked) {
  MasterRig rig({test_axis(1, cia402::csp), test_axis(2, cia402::cst)});
  rig.start();
  ASSERT_EQ(rig.master.set_setpoint(0, 1.0), Codec::ok);
  EXPECT_EQ(rig.master.set_setpoint(0, std::nan("")), Codec::invalid);
  EXPECT_EQ(rig.master.set_setpoint(0, 1e9), Codec::too_high);
  EXPECT_EQ(rig.master.setpoint(0), 1.0);
  EXPECT_EQ(rig.master.set_setpoint(1, 1e3), Codec::too_high) << "2000 x rated torque";
  rig.cycle();
  EXPECT_EQ(rig.drives[0].target_position(), 652) << "1 rad in 4096 counts/turn";
}

TEST(CanopenMaster, ASilentDriveIsLostWithinItsHeartbeatTimeout) {
  MasterRig rig({test_axis(1, cia402::csp), test_axis(2, cia402::csp)});
  rig.start();
  for (int i = 0; i < 20; ++i) rig.cycle();
  EXPECT_TRUE(rig.master.health(1).heartbeat_seen);
  rig.drives[1].set_silent(true);
  const TimeNs silent_at = rig.now;
  while (!rig.master.health(1).heartbeat_lost && rig.now < silent_at + 100 * ms) rig.cycle();
  EXPECT_TRUE(rig.master.health(1).heartbeat_lost);
  // The last heartbeat came up to one period before silence; lost once 30 ms passed after it.
  EXPECT_LE(rig.now - silent_at, 32 * ms);
  EXPECT_GE(rig.master.health(1).silent_for, 30 * ms);
  EXPECT_FALSE(rig.master.health(0).heartbeat_lost);
  rig.drives[1].set_silent(false);
  for (int i = 0; i < 20; ++i) rig.cycle();
  EXPECT_FALSE(rig.master.health(1).heartbeat_lost) << "back";
  EXPECT_EQ(rig.master.health(1).heartbeat_losses, 1u);
}

TEST(CanopenMaster, EmcyIsDecodedForItsDrive) {
  MasterRig rig({test_axis(1, cia402::csp), test_axis(2, cia402::csp)});
  rig.start();
  rig.enable_all();
  for (int i = 0; i < 20; ++i) rig.cycle();
  rig.drives[1].raise_fault(0x2310);
  for (int i = 0; i < 5; ++i) rig.cycle();
  EXPECT_EQ(rig.master.health(1).emcy_count, 1u);
  EXPECT_EQ(rig.master.health(1).last_emcy, 0x2310);
  EXPECT_EQ(rig.master.health(0).emcy_count, 0u);
  EXPECT_EQ(rig.master.feedback(1).state, cia402::State::fault);
  EXPECT_EQ(rig.master.control(1).progress, cia402::Progress::fault);
  // Cleared, reset and enabled again.
  rig.drives[1].clear_fault();
  rig.master.request_fault_reset(1, rig.now);
  for (int i = 0; i < 30; ++i) rig.cycle();
  EXPECT_EQ(rig.master.feedback(1).state, cia402::State::operation_enabled);
  EXPECT_EQ(rig.master.health(1).error_register, 0) << "the error reset EMCY";
}

TEST(CanopenMaster, RuntimeSdoGoesThroughTheQueue) {
  BusMasterConfig config;
  config.sdo_queue = 2;
  MasterRig rig({test_axis(5, cia402::csp)}, config);
  rig.start();
  SdoQueue& q = rig.master.sdo_queue();
  SdoRequest read;
  read.tag = 7;
  read.node = 5;
  read.index = 0x1000;
  ASSERT_EQ(q.submit(read), saw::Status::ok);
  SdoRequest write;
  write.tag = 8;
  write.node = 5;
  write.index = 0x1017;
  write.write = true;
  write.size = 2;
  write.data = {20, 0};
  ASSERT_EQ(q.submit(write), saw::Status::ok);
  EXPECT_EQ(q.submit(write), saw::Status::queue_full) << "a full queue is an error, not a wait";
  EXPECT_EQ(q.refused(), 1u);
  SdoRequest nobody = read;
  nobody.node = 9;
  std::vector<SdoReply> replies;
  for (int i = 0; i < 10; ++i) {
    rig.cycle();
    if (i == 0) {
      ASSERT_EQ(q.submit(nobody), saw::Status::ok);
    }
    for (SdoReply r; q.take_reply(r);) replies.push_back(r);
  }
  ASSERT_EQ(replies.size(), 3u);
  EXPECT_EQ(replies[0].tag, 7u);
  EXPECT_TRUE(replies[0].ok());
  EXPECT_EQ(replies[0].size, 4);
  EXPECT_EQ(replies[0].data[0], 0x92);
  EXPECT_EQ(replies[0].data[2], 0x02);
  EXPECT_EQ(replies[1].tag, 8u);
  EXPECT_TRUE(replies[1].ok());
  EXPECT_EQ(replies[2].status, saw::Status::invalid) << "no node 9 on this bus";
  std::uint16_t hb = 0;
  (void)rig.drives[0].dictionary().get({0x1017, 0}, hb);
  EXPECT_EQ(hb, 20);
  EXPECT_EQ(rig.master.counters().sdo_done, 2u);
}

TEST(CanopenMaster, RefusesTwoDrivesOnOneNode) {
  RingNetwork network;
  RingPort& port = network.attach("master");
  EXPECT_THROW(BusMaster(port, {}, {test_axis(4, cia402::csp), test_axis(4, cia402::csp)}),
               std::invalid_argument);
  AxisConfig no_target = test_axis(1, cia402::csv);
  no_target.pdos = default_pdo_mappings(cia402::csp, 1);
  try {
    BusMaster m(port, {}, {no_target});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no RPDO maps the mode's target (0x60FF:00)"), std::string::npos)
        << e.what();
  }
}

}  // namespace
