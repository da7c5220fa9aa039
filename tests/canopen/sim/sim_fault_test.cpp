// Fault injection in the simulated drive: each fault's EMCY, the drive's fault state and the
// recovery by fault reset; heartbeat loss seen by the protocol library's consumer; bus-off;
// SDO aborts; and injection through the bus itself (0x2F00).
#include <gtest/gtest.h>

#include <cmath>

#include "saw/canopen/sim/drive_dictionary.hpp"
#include "sim_master.hpp"

namespace saw::canopen::sim {
namespace {

using namespace testing;
namespace obj = cia402::object;

struct EventCase {
  FaultKind kind;
  std::uint16_t code;
  std::uint8_t register_bits;
};

class SimDriveEventFault : public ::testing::TestWithParam<EventCase> {};

TEST_P(SimDriveEventFault, RaisesEmcyFaultsTheDriveAndRecoversOnFaultReset) {
  const EventCase c = GetParam();
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::csp);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  b.drive.inject({c.kind});
  ASSERT_TRUE(b.run_until([&] { return m.last.progress == cia402::Progress::fault; }, 100 * ms));
  EXPECT_EQ(b.drive.drive_state(), cia402::State::fault);
  EXPECT_NE(m.statusword & cia402::statusword::fault, 0);
  ASSERT_EQ(b.emcys().size(), 1u);
  const Emcy e = b.emcys()[0];
  EXPECT_EQ(e.code, c.code) << emcy_name(e.code);
  EXPECT_EQ(e.error_register, c.register_bits | error_register::generic);
  EXPECT_EQ(b.upload_value<std::uint16_t>(obj::error_code, DataType::unsigned16), c.code);
  EXPECT_EQ(b.upload_value<std::uint8_t>({0x1001, 0}, DataType::unsigned8), e.error_register);
  EXPECT_EQ(b.upload_value<std::uint8_t>({0x1003, 0}, DataType::unsigned8), 1u);
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1003, 1}, DataType::unsigned32), c.code);

  m.controller.request_fault_reset(b.now);
  ASSERT_TRUE(b.run_until([&] { return m.last.progress == cia402::Progress::reached; }, 200 * ms))
      << "fault reset, then on to operation enabled again";
  EXPECT_EQ(b.drive.drive_state(), cia402::State::operation_enabled);
  ASSERT_EQ(b.emcys().size(), 2u);
  EXPECT_TRUE(b.emcys()[1].is_reset());
  EXPECT_EQ(b.emcys()[1].error_register, 0);
  EXPECT_EQ(b.drive.error_code(), 0);
}

INSTANTIATE_TEST_SUITE_P(
    Faults, SimDriveEventFault,
    ::testing::Values(EventCase{FaultKind::over_current, 0x2310, error_register::current},
                      EventCase{FaultKind::following_error, 0x8611, error_register::device_profile}),
    [](const auto& param_info) {
      return param_info.param.kind == FaultKind::over_current ? "OverCurrent" : "FollowingError";
    });

TEST(SimDriveFault, ExceedingTheFollowingErrorWindowFaultsTheDrive) {
  Bench b;
  Master m(b);
  b.tick();
  b.write(obj::following_error_window, DataType::unsigned32, 100u);
  b.write({0x6066, 0}, DataType::unsigned16, std::uint16_t{5});
  m.start(cia402::csp);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  m.target_position = 50'000;  // a step no servo follows within 100 counts
  std::uint16_t bits = 0;
  ASSERT_TRUE(b.run_until(
      [&] {
        bits |= m.statusword;
        return b.drive.drive_state() == cia402::State::fault;
      },
      100 * ms));
  ASSERT_EQ(b.emcys().size(), 1u);
  EXPECT_EQ(b.emcys()[0].code, 0x8611);
  EXPECT_NE(bits & cia402::statusword::mode_specific_13, 0) << "CSP's following error bit, before the fault";
}

TEST(SimDriveFault, HeartbeatLossIsSeenByTheConsumerAndEnds) {
  Bench b;
  b.heartbeats.watch(b.node, 25 * ms);
  b.tick();
  b.write({0x1017, 0}, DataType::unsigned16, std::uint16_t{10});
  b.run_for(100 * ms);
  Fault f{FaultKind::heartbeat_loss};
  f.duration = 200 * ms;
  const std::size_t first = b.events.size();
  b.drive.inject(f);
  b.run_for(100 * ms);
  EXPECT_EQ(b.drive.active_faults(), fault_bit(FaultKind::heartbeat_loss));
  EXPECT_EQ(b.upload_value<std::uint8_t>(injection_object::active, DataType::unsigned8),
            fault_bit(FaultKind::heartbeat_loss))
      << "SDO carries on";
  b.run_for(200 * ms);
  std::vector<HeartbeatEvent::Kind> kinds;
  for (std::size_t i = first; i < b.events.size(); ++i) kinds.push_back(b.events[i].kind);
  const std::vector<HeartbeatEvent::Kind> expected = {HeartbeatEvent::Kind::lost, HeartbeatEvent::Kind::back};
  ASSERT_EQ(kinds, expected);
  EXPECT_GE(b.events[first + 1].silent_for, 200 * ms);
  EXPECT_LE(b.events[first].late_by, 1 * ms) << "detected within a step of the consumer time";
  EXPECT_EQ(b.drive.active_faults(), 0);
  EXPECT_TRUE(b.emcys().empty()) << "a silent heartbeat is the consumer's to notice";
}

TEST(SimDriveFault, BusOffSilencesTheNodeThenItReportsTheRecovery) {
  Bench b;
  b.tick();
  b.write({0x1017, 0}, DataType::unsigned16, std::uint16_t{10});
  b.nmt(NmtCommand::start);
  b.run_for(50 * ms);
  Fault f{FaultKind::bus_off};
  f.duration = 300 * ms;
  b.drive.inject(f);
  b.tick();
  ASSERT_TRUE(b.drive.bus_off());
  const std::size_t before = b.seen.size();
  ASSERT_TRUE(b.sdo.upload({0x1000, 0}, b.now));
  b.run_for(250 * ms);
  EXPECT_EQ(b.seen.size(), before) << "nothing from the node";
  b.run_until([&] { return !b.sdo.busy(); }, 1000 * ms);
  EXPECT_EQ(b.sdo.result().abort, SdoAbort::timeout) << "its request was lost";
  EXPECT_FALSE(b.drive.bus_off());
  EXPECT_GT(b.drive.counters().lost_bus_off, 25u) << "heartbeats and the SDO request";
  ASSERT_EQ(b.emcys().size(), 2u);
  EXPECT_EQ(b.emcys()[0].code, 0x8140) << emcy_name(0x8140);
  EXPECT_NE(b.emcys()[0].error_register & error_register::communication, 0);
  EXPECT_TRUE(b.emcys()[1].is_reset());
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1000, 0}, DataType::unsigned32), 0x00020192u);
  EXPECT_EQ(b.drive.nmt_state(), NmtState::operational) << "bus-off is not a reset";
}

TEST(SimDriveFault, BusOffFaultsAnEnabledDriveAs0x6007Says) {
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::csv);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  Fault f{FaultKind::bus_off};
  f.duration = 100 * ms;
  b.drive.inject(f);
  b.run_for(50 * ms);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::fault) << "0x6007 = 1 in sim_drive.eds: fault signal";
  EXPECT_TRUE(b.emcys().empty()) << "nothing gets out during bus-off";
  ASSERT_TRUE(b.run_until([&] { return !b.emcys().empty(); }, 100 * ms));
  b.run_for(5 * ms);
  ASSERT_EQ(b.emcys().size(), 1u) << "the queued EMCY, and no reset: the fault is still there";
  EXPECT_EQ(b.emcys()[0].code, 0x8140);
  EXPECT_EQ(b.drive.error_code(), 0x8140);
  m.controller.request_fault_reset(b.now);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  ASSERT_EQ(b.emcys().size(), 2u);
  EXPECT_TRUE(b.emcys()[1].is_reset());
}

TEST(SimDriveFault, BusOffWithAbortConnectionQuickStopStopsTheDrive) {
  Bench b;
  Master m(b);
  b.tick();
  b.write({0x6007, 0}, DataType::integer16, std::int16_t{3});
  m.start(cia402::csv);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  m.target_velocity = 10 * 4096;
  b.run_for(100 * ms);
  Fault f{FaultKind::bus_off};
  f.duration = 200 * ms;
  b.drive.inject(f);
  b.run_for(2 * ms);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::quick_stop_active);
  b.run_for(150 * ms);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::switch_on_disabled) << "quick stop option 2";
  EXPECT_LT(std::abs(b.drive.motor().velocity()), 0.1);
}

TEST(SimDriveFault, AMasterWhoseHeartbeatStopsIsNoticedByTheConsumerAndTheDriveStops) {
  Bench b;
  Master m(b);
  b.tick();
  b.write({0x1016, 1}, DataType::unsigned32, std::uint32_t{127u << 16 | 50u});  // node 127, 50 ms
  b.write({0x6007, 0}, DataType::integer16, std::int16_t{3});                   // quick stop
  m.start(cia402::csv);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  m.target_velocity = 10 * 4096;
  b.run_for(100 * ms);
  EXPECT_EQ(b.drive.counters().heartbeat_events, 0u) << "not watched before the master's first heartbeat";
  for (int i = 0; i < 10; ++i) {  // the master's heartbeat, every 20 ms
    b.send(heartbeat_frame(127, NmtState::operational));
    b.run_for(20 * ms);
  }
  EXPECT_EQ(b.drive.drive_state(), cia402::State::operation_enabled);
  EXPECT_EQ(b.drive.counters().heartbeat_events, 0u);
  // The master dies: its heartbeat and everything else stop, the last RPDO stays.
  b.each_tick = {};
  const TimeNs last = b.now - 20 * ms;
  b.run_for(25 * ms);  // 45 ms since its last heartbeat
  EXPECT_EQ(b.drive.drive_state(), cia402::State::operation_enabled) << "within the consumer time";
  ASSERT_TRUE(b.run_until([&] { return b.drive.counters().heartbeat_events == 1; }, 100 * ms));
  EXPECT_GT(b.now - last, 50 * ms);
  EXPECT_LE(b.now - last, 52 * ms) << "within a step or two of the consumer time";
  b.run_for(2 * ms);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::quick_stop_active) << "0x6007 = 3";
  ASSERT_FALSE(b.emcys().empty());
  EXPECT_EQ(b.emcys().back().code, 0x8130) << emcy_name(0x8130);
  b.run_for(150 * ms);
  EXPECT_LT(std::abs(b.drive.motor().velocity()), 0.1) << "stopped by itself";
}

// CiA 301's RPDO deadline (0x1400+k:05, ms): a master whose RPDOs stop while its SYNC goes on
// (a starved cycle) is seen by the drive: EMCY 0x8250, then what 0x6007 says; 0 does not watch.
TEST(SimDriveFault, RpdosThatMissTheirDeadlineRaise0x8250AndTheDriveDoesWhat6007Says) {
  for (const std::uint16_t deadline : {std::uint16_t{5}, std::uint16_t{0}}) {
    Bench b;
    Master m(b);
    b.tick();
    b.write({0x6007, 0}, DataType::integer16, std::int16_t{3});  // quick stop
    m.start(cia402::csv);
    for (std::uint16_t k = 0; k < 3; ++k)
      b.write({static_cast<std::uint16_t>(0x1400 + k), 5}, DataType::unsigned16, deadline);
    ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
    m.target_velocity = 10 * 4096;
    b.run_for(50 * ms);
    EXPECT_EQ(b.drive.counters().rpdo_timeouts, 0u) << "every RPDO in time";
    // Only SYNC goes on: the master's cycle is starved, its bus is not.
    b.each_tick = [&b] {
      if (b.now % ms == 0) b.send(sync_frame());
    };
    const TimeNs last = b.now - ms;
    if (deadline == 0) {
      b.run_for(100 * ms);
      EXPECT_EQ(b.drive.counters().rpdo_timeouts, 0u) << "0: not watched";
      EXPECT_EQ(b.drive.drive_state(), cia402::State::operation_enabled) << "its last setpoints, still";
      continue;
    }
    ASSERT_TRUE(b.run_until([&] { return b.drive.counters().rpdo_timeouts >= 1; }, 50 * ms));
    EXPECT_GT(b.now - last, 5 * ms);
    EXPECT_LE(b.now - last, 7 * ms) << "within a step or two of the deadline";
    b.run_for(2 * ms);
    EXPECT_EQ(b.drive.counters().rpdo_timeouts, 3u) << "each RPDO once per silence";
    EXPECT_EQ(b.drive.drive_state(), cia402::State::quick_stop_active) << "0x6007 = 3";
    EXPECT_EQ(b.drive.nmt_state(), NmtState::operational) << "its master's SYNC goes on";
    ASSERT_FALSE(b.emcys().empty());
    EXPECT_EQ(b.emcys().front().code, 0x8250) << emcy_name(0x8250);
    b.run_for(150 * ms);
    EXPECT_LT(std::abs(b.drive.motor().velocity()), 0.1) << "stopped by itself";
  }
}

TEST(SimDriveFault, SdoAbortOnOneObjectUntilCleared) {
  Bench b;
  b.tick();
  Fault f{FaultKind::sdo_abort};
  f.object = obj::position_actual_value;
  f.abort = SdoAbort::hardware;
  b.drive.inject(f);
  b.tick();
  SdoResult r = b.upload(obj::position_actual_value);
  EXPECT_EQ(r.status, SdoStatus::failed);
  EXPECT_TRUE(r.remote);
  EXPECT_EQ(r.abort, SdoAbort::hardware);
  EXPECT_EQ(b.download(obj::position_actual_value, DataType::integer32, 0).abort, SdoAbort::hardware);
  EXPECT_EQ(b.upload_value<std::uint32_t>({0x1000, 0}, DataType::unsigned32), 0x00020192u)
      << "others are served";
  b.drive.clear(FaultKind::sdo_abort);
  EXPECT_EQ(b.upload(obj::position_actual_value).status, SdoStatus::done);
}

TEST(SimDriveFault, FaultsAreInjectedThroughTheBusBy0x2F00) {
  Bench b;
  b.tick();
  b.nmt(NmtCommand::start);
  b.write(injection_object::object, DataType::unsigned32, 0x10080000u);
  b.write(injection_object::code, DataType::unsigned32, 0x08000020u);
  b.write(injection_object::inject, DataType::unsigned8, std::uint8_t{5});
  b.tick();
  EXPECT_EQ(b.upload({0x1008, 0}).abort, static_cast<SdoAbort>(0x08000020u));
  EXPECT_EQ(b.upload_value<std::uint8_t>(injection_object::active, DataType::unsigned8),
            fault_bit(FaultKind::sdo_abort));
  b.write(injection_object::inject, DataType::unsigned8, std::uint8_t{0});
  b.tick();
  EXPECT_EQ(b.upload({0x1008, 0}).status, SdoStatus::done) << "0 clears";
  b.write(injection_object::inject, DataType::unsigned8, std::uint8_t{1});
  b.run_for(5 * ms);
  ASSERT_EQ(b.emcys().size(), 1u);
  EXPECT_EQ(b.emcys()[0].code, 0x2310);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::fault);
  EXPECT_EQ(b.download(injection_object::inject, DataType::unsigned8, std::uint8_t{9}).abort,
            SdoAbort::value_too_high);
  b.write(injection_object::duration, DataType::unsigned32, 100u);
  b.write(injection_object::inject, DataType::unsigned8, std::uint8_t{4});
  b.run_for(50 * ms);
  EXPECT_TRUE(b.drive.bus_off()) << "after the write's response went out";
  b.run_for(60 * ms);
  EXPECT_FALSE(b.drive.bus_off()) << "its duration from 0x2F00:02";
}

}  // namespace
}  // namespace saw::canopen::sim
