// CiA 301's RPDO deadline monitoring: the master writes each RPDO's event timer (rpdo_deadline),
// a drive whose RPDOs stop while SYNC and heartbeats go on signals EMCY 0x8250 and does what 0x6007
// says, and the arm faults on that EMCY; off, the same stall leaves the drives driving.
#include "saw/canopen/rpdo_deadline.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "arm_rig.hpp"
#include "saw/canopen/eds.hpp"
#include "shared_rig.hpp"

namespace saw::canopen::test {
namespace {

// The event timer writes the drive acknowledged, by RPDO number (value in ms).
std::vector<std::pair<std::uint16_t, std::uint32_t>> timer_writes(TestDrive& d) {
  std::vector<std::pair<std::uint16_t, std::uint32_t>> out;
  for (const TestDrive::Write& w : d.writes())
    if (w.address.index >= 0x1400 && w.address.index < 0x1600 && w.address.subindex == 5)
      out.emplace_back(static_cast<std::uint16_t>(w.address.index - 0x1400 + 1), w.value);
  return out;
}

std::vector<std::uint16_t> enabled_rpdos(CanopenArm& arm, std::size_t axis) {
  std::vector<std::uint16_t> out;
  for (const PdoMapping& m : arm.master().axis(axis).pdos)
    if (m.kind == PdoKind::rpdo && m.enabled) out.push_back(m.number);
  return out;
}

int emcys(const std::vector<can::Frame>& frames, std::uint8_t node, std::uint16_t code) {
  return static_cast<int>(std::count_if(frames.begin(), frames.end(), [&](const can::Frame& f) {
    return f.can_id() == 0x80u + node && f.len == 8 && f.data[0] == (code & 0xFF) && f.data[1] == code >> 8;
  }));
}

TEST(CanopenRpdoDeadline, ResolvedInWholeMsAtLeastTwoPeriods) {
  constexpr TimeNs period = 1'000'000;
  EXPECT_EQ(resolve_rpdo_deadline(std::nullopt, period), 5 * ms) << "5 ms at 1 kHz";
  EXPECT_EQ(resolve_rpdo_deadline(std::nullopt, 4 * ms), 12 * ms) << "3 periods beyond 5 ms";
  EXPECT_EQ(resolve_rpdo_deadline(2'500'000, period), 3 * ms) << "rounded up, never shortened";
  EXPECT_EQ(resolve_rpdo_deadline(0, period), 0);
  EXPECT_THROW((void)resolve_rpdo_deadline(1'000'000, period), std::invalid_argument) << "one period";
  EXPECT_EQ(resolve_rpdo_deadline(1'500'000, period), 2 * ms) << "2 ms in whole ms: two periods";
  EXPECT_THROW((void)resolve_rpdo_deadline(66 * 1'000'000'000LL, period), std::invalid_argument);
  EXPECT_EQ(deadline_ms(65'535 * ms), 65'535);
}

// The master's start-up writes 0x1400+k:05 to every enabled RPDO, and a re-configuration after a
// reboot writes it again (the reboot took it back to 0).
TEST(CanopenRpdoDeadline, TheMasterWritesEachRpdosEventTimerAtStartUpAndAfterAReboot) {
  auto c = arm_config(cia402::csp, 2);
  c.rpdo_deadline = 2'500'000;
  ArmRig rig(c);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto rpdos = enabled_rpdos(*rig.arm, i);
    ASSERT_FALSE(rpdos.empty());
    std::vector<std::pair<std::uint16_t, std::uint32_t>> expected;
    for (const std::uint16_t n : rpdos) expected.emplace_back(n, 3u);  // 2.5 ms: 3 ms
    EXPECT_EQ(timer_writes(rig.drives[i]), expected) << "drive " << i;
  }
  rig.enable();
  ASSERT_EQ(rig.state(), OperatingStateValue::enabled);
  rig.drives[0].reboot();
  rig.cycle(3);
  ASSERT_EQ(rig.arm->fault_reason(), FaultReason::node_rebooted);
  rig.enable();
  ASSERT_EQ(rig.state(), OperatingStateValue::enabled);
  const auto again = timer_writes(rig.drives[0]);
  ASSERT_EQ(again.size(), 2 * enabled_rpdos(*rig.arm, 0).size()) << "written again";
  EXPECT_EQ(again.back().second, 3u);
}

// The arm as a client of a bus task: the bus task's SYNC and the master's heartbeat go on while
// the arm's cycle does not run (a starved task), so only its RPDOs stop.
struct Stall {
  explicit Stall(const std::function<void(CanopenArmConfig&)>& edit) {
    arm = rig.make("arm", {1, 2}, edit);
    arm->startup();
    rig.cycle({arm.get()}, 60);
  }
  void starve(int cycles) {
    rig.seen.clear();
    rig.cycle({}, cycles);
  }
  // `enable` as a client sends it: run at the arm's next cycle.
  void enable() {
    if (!mailbox) {
      mailbox = std::make_unique<detail::Mailbox>("test client", 8, sizeof(StateCommand));
      detail::Access::add_inbound(*arm, mailbox.get());
      state = mailbox->add_target(execute_of(*arm->provided("arm")->find_command("state_command")));
    }
    const StateCommand c = StateCommand::enable;
    ASSERT_EQ(mailbox->push(state, &c, sizeof c), Status::ok);
  }
  SharedRig rig;
  std::unique_ptr<detail::Mailbox> mailbox;  // before the arm: it outlives the arm's reference
  std::uint32_t state = 0;
  std::unique_ptr<CanopenArm> arm;
};

TEST(CanopenRpdoDeadline, ADriveWhoseRpdosStopDoesWhat6007SaysAndTheArmFaultsOnItsEmcy) {
  const std::pair<AbortConnection, cia402::State> cases[] = {
      {AbortConnection::quick_stop, cia402::State::switch_on_disabled},  // 0x605A: 2, at standstill
      {AbortConnection::fault, cia402::State::fault},
      {AbortConnection::disable_voltage, cia402::State::switch_on_disabled}};
  for (const auto& [option, expected] : cases) {
    const int n = static_cast<int>(option);
    Stall s([option = option](CanopenArmConfig& c) { c.abort_connection = option; });
    ASSERT_EQ(s.arm->operating_state().state, OperatingStateValue::enabled) << n;
    s.starve(4);  // 4 ms: within the 5 ms deadline
    EXPECT_EQ(s.rig.drives[0].state(), cia402::State::operation_enabled) << n;
    s.starve(6);
    for (std::size_t i = 0; i < 2; ++i) {
      TestDrive& d = s.rig.drives[i];
      EXPECT_EQ(d.rpdo_timeouts(), enabled_rpdos(*s.arm, i).size()) << n;
      EXPECT_EQ(d.state(), expected) << "option " << n;
      EXPECT_EQ(d.heartbeat_events(), 0u) << "the master's heartbeat went on";
      EXPECT_EQ(d.nmt_state(), NmtState::operational) << "its master is alive: it stays operational";
    }
    EXPECT_GE(emcys(s.rig.seen, 1, 0x8250), 1) << n;
    EXPECT_GE(emcys(s.rig.seen, 2, 0x8250), 1) << n;
    // The arm's next cycle reads the EMCY: its FAULT names the drive and the code.
    s.rig.cycle({s.arm.get()}, 2);
    EXPECT_EQ(s.arm->operating_state().state, OperatingStateValue::fault) << n;
    EXPECT_EQ(s.arm->fault_reason(), FaultReason::emcy) << n;
    EXPECT_EQ(s.arm->device_status().fault.detail, 0x8250u) << n;
    EXPECT_EQ(s.arm->device_status().fault.source_name(), "n1") << n;
    // An enable walks the drives back (fault reset where 0x6007 faulted them); their RPDOs come
    // again, so their deadlines are watched again, and quiet.
    s.enable();
    s.rig.cycle({s.arm.get()}, 60);
    EXPECT_EQ(s.arm->operating_state().state, OperatingStateValue::enabled) << n;
    EXPECT_EQ(s.rig.drives[0].state(), cia402::State::operation_enabled) << n;
    EXPECT_EQ(s.rig.drives[0].rpdo_timeouts(), enabled_rpdos(*s.arm, 0).size()) << "no new one";
  }
}

TEST(CanopenRpdoDeadline, OffTheSameStallLeavesTheDrivesDriving) {
  Stall s([](CanopenArmConfig& c) { c.rpdo_deadline = 0; });
  const auto written = timer_writes(s.rig.drives[0]);
  ASSERT_FALSE(written.empty());
  EXPECT_EQ(written.front().second, 0u) << "0 written: a device default goes off";
  s.starve(10);
  EXPECT_EQ(s.rig.drives[0].rpdo_timeouts(), 0u);
  EXPECT_EQ(s.rig.drives[0].state(), cia402::State::operation_enabled);
  EXPECT_EQ(emcys(s.rig.seen, 1, 0x8250), 0);
  s.rig.cycle({s.arm.get()}, 5);
  EXPECT_EQ(s.arm->operating_state().state, OperatingStateValue::enabled);
}

// An EDS that lists no writable event timer: that RPDO is not asked (tests/canopen/data/drive.eds
// has none; saw-can-sim's built-in one lists them rw).
TEST(CanopenRpdoDeadline, AnEdsWithoutAWritableEventTimerIsNotAsked) {
  const Eds eds = load_eds(SAW_CANOPEN_TEST_DATA "/drive.eds");
  const auto pdos = eds_pdo_mappings(eds, 1);
  std::vector<std::uint16_t> enabled;
  for (const PdoMapping& m : pdos)
    if (m.kind == PdoKind::rpdo && m.enabled) enabled.push_back(m.number);
  ASSERT_FALSE(enabled.empty());
  EXPECT_EQ(rpdos_without_event_timer(eds, pdos), enabled);
  RpdoDeadline d{5 * ms, enabled};
  const auto writes = node_writes(pdos, 100 * ms, 127, 300 * ms, d);
  EXPECT_TRUE(std::none_of(writes.begin(), writes.end(), [](const StartupWrite& w) {
    return w.write.address.index >= 0x1400 && w.write.address.index < 0x1600 && w.write.address.subindex == 5;
  }));
  EXPECT_EQ(unwatched_rpdos(pdos, d, {}), enabled) << "what open() warns about";
}

}  // namespace
}  // namespace saw::canopen::test
