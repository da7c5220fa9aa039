// CiA 402: statusword and controlword coding, every transition of the drive-side state machine,
// the master-side controller against that drive model, and unit conversions.
#include "saw/canopen/cia402.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/cia402_drive.hpp"
#include "saw/canopen/units.hpp"

namespace {

using namespace saw::canopen;
using namespace saw::canopen::cia402;
using saw::TimeNs;

constexpr TimeNs ms = 1'000'000;

TEST(CanopenCia402, StatuswordDecodesEveryState) {
  EXPECT_EQ(decode_state(0x0000), State::not_ready_to_switch_on);
  EXPECT_EQ(decode_state(0x0250), State::switch_on_disabled);  // as drives send it: voltage, remote
  EXPECT_EQ(decode_state(0x0270), State::switch_on_disabled);  // quick-stop bit is "x" there
  EXPECT_EQ(decode_state(0x0231), State::ready_to_switch_on);
  EXPECT_EQ(decode_state(0x0233), State::switched_on);
  EXPECT_EQ(decode_state(0x1637), State::operation_enabled);  // target reached, following
  EXPECT_EQ(decode_state(0x0217), State::quick_stop_active);
  EXPECT_EQ(decode_state(0x021F), State::fault_reaction_active);
  EXPECT_EQ(decode_state(0x0218), State::fault);
  EXPECT_EQ(decode_state(0x0238), State::fault);
  EXPECT_EQ(decode_state(0x0001), State::unknown);
  EXPECT_EQ(decode_state(0x0061), State::unknown);  // ready bits with switch on disabled set
  for (State s : {State::not_ready_to_switch_on, State::switch_on_disabled, State::ready_to_switch_on,
                  State::switched_on, State::operation_enabled, State::quick_stop_active,
                  State::fault_reaction_active, State::fault})
    EXPECT_EQ(decode_state(state_statusword(s)), s) << to_string(s);
}

TEST(CanopenCia402, ControlwordCommands) {
  EXPECT_EQ(decode_command(0x0006), Command::shutdown);
  EXPECT_EQ(decode_command(0x000E), Command::shutdown);
  EXPECT_EQ(decode_command(0x0007), Command::switch_on);
  EXPECT_EQ(decode_command(0x000F), Command::enable_operation);
  EXPECT_EQ(decode_command(0x0000), Command::disable_voltage);
  EXPECT_EQ(decode_command(0x000D), Command::disable_voltage);
  EXPECT_EQ(decode_command(0x0002), Command::quick_stop);
  EXPECT_EQ(decode_command(0x000B), Command::quick_stop);
  EXPECT_EQ(decode_command(0x010F), Command::enable_operation) << "halt is not a state command";
  EXPECT_EQ(decode_command(0x008F), Command::none) << "bit 7 set: fault reset only";
}

TEST(CanopenCia402, ModesAndTheirSupportBits) {
  EXPECT_EQ(static_cast<int>(csp), 8);
  EXPECT_EQ(static_cast<int>(csv), 9);
  EXPECT_EQ(static_cast<int>(cst), 10);
  EXPECT_EQ(static_cast<int>(Mode::profile_position), 1);
  EXPECT_EQ(static_cast<int>(Mode::homing), 6);
  EXPECT_EQ(supported_mode_bit(csp), 0x80u);
  EXPECT_EQ(supported_mode_bit(cst), 0x200u);
  EXPECT_EQ(supported_mode_bit(Mode::profile_position), 0x01u);
  EXPECT_EQ(supported_mode_bit(static_cast<Mode>(5)), 0u);
  EXPECT_EQ(supported_mode_bit(static_cast<Mode>(-1)), 0u);
  EXPECT_EQ(to_string(csp), "cyclic synchronous position");
  EXPECT_EQ(to_string(static_cast<Mode>(-3)), "manufacturer-specific mode");
  Drive d;
  EXPECT_TRUE(d.request_mode(csv));
  EXPECT_FALSE(d.request_mode(Mode::profile_position));
  EXPECT_EQ(d.mode_display(), csv);
}

// --- the drive: every transition of the figure -------------------------------------------

DriveInput cw(std::uint16_t controlword, bool standstill = true) {
  return {controlword, false, standstill, true};
}
DriveInput fault_input(bool standstill = false) { return {0x000F, true, standstill, true}; }

// A drive brought to `s` the standard way.
Drive drive_in(State s, DriveConfig config = {}) {
  Drive d(config);
  if (s == State::not_ready_to_switch_on) return d;
  d.update(cw(0x0000));
  switch (s) {
    case State::switch_on_disabled:
      break;
    case State::ready_to_switch_on:
      d.update(cw(0x0006));
      break;
    case State::switched_on:
      d.update(cw(0x0006));
      d.update(cw(0x0007));
      break;
    case State::operation_enabled:
    case State::quick_stop_active:
      d.update(cw(0x0006));
      d.update(cw(0x0007));
      d.update(cw(0x000F));
      if (s == State::quick_stop_active) d.update(cw(0x0002, false));
      break;
    case State::fault_reaction_active:
      d.update(fault_input());
      break;
    case State::fault:
      d.update(fault_input());
      d.update(fault_input(true));
      break;
    default:
      break;
  }
  EXPECT_EQ(d.state(), s) << "set-up of " << to_string(s);
  return d;
}

struct Transition {
  int number;
  State from;
  std::vector<DriveInput> inputs;
  State to;
  DriveConfig config = {};
};

TEST(CanopenCia402Drive, TakesEveryTransitionOfTheFigure) {
  DriveConfig stay;  // quick stop option codes 5..8 stay in quick stop active
  stay.quick_stop_option = 6;
  DriveConfig immediate;
  immediate.quick_stop_option = 0;
  const std::vector<Transition> transitions = {
      {1, State::not_ready_to_switch_on, {cw(0x0000)}, State::switch_on_disabled},
      {2, State::switch_on_disabled, {cw(0x0006)}, State::ready_to_switch_on},
      {3, State::ready_to_switch_on, {cw(0x0007)}, State::switched_on},
      {3, State::ready_to_switch_on, {cw(0x000F)}, State::switched_on},  // switch on + enable: 3 first
      {4, State::switched_on, {cw(0x000F)}, State::operation_enabled},
      {4, State::ready_to_switch_on, {cw(0x000F), cw(0x000F)}, State::operation_enabled},  // ... then 4
      {5, State::operation_enabled, {cw(0x0007)}, State::switched_on},
      {6, State::switched_on, {cw(0x0006)}, State::ready_to_switch_on},
      {7, State::ready_to_switch_on, {cw(0x0000)}, State::switch_on_disabled},
      {7, State::ready_to_switch_on, {cw(0x0002)}, State::switch_on_disabled},
      {8, State::operation_enabled, {cw(0x0006)}, State::ready_to_switch_on},
      {9, State::operation_enabled, {cw(0x0000)}, State::switch_on_disabled},
      {10, State::switched_on, {cw(0x0000)}, State::switch_on_disabled},
      {10, State::switched_on, {cw(0x0002)}, State::switch_on_disabled},
      {11, State::operation_enabled, {cw(0x0002, false)}, State::quick_stop_active},
      {12, State::quick_stop_active, {cw(0x0000, false)}, State::switch_on_disabled},
      {12, State::quick_stop_active, {cw(0x0002, true)}, State::switch_on_disabled},  // ramp done (option 2)
      {12, State::operation_enabled, {cw(0x0002, false)}, State::switch_on_disabled, immediate},
      {12, State::quick_stop_active, {cw(0x0000)}, State::switch_on_disabled, stay},
      {14, State::fault_reaction_active, {fault_input(true)}, State::fault},
      {15, State::fault, {cw(0x0000), cw(0x0080)}, State::switch_on_disabled},
      {16, State::quick_stop_active, {cw(0x000F, false)}, State::operation_enabled, stay},
  };
  for (const auto& t : transitions) {
    SCOPED_TRACE("transition " + std::to_string(t.number) + " from " + std::string(to_string(t.from)));
    Drive d = drive_in(t.from, t.config);
    for (const auto& in : t.inputs) d.update(in);
    EXPECT_EQ(d.state(), t.to) << to_string(d.state());
    EXPECT_EQ(d.last_transition(), t.number);
    EXPECT_EQ(decode_state(d.statusword()), t.to);
  }
}

TEST(CanopenCia402Drive, FaultEntersFromEveryState) {
  for (State s : {State::not_ready_to_switch_on, State::switch_on_disabled, State::ready_to_switch_on,
                  State::switched_on, State::operation_enabled, State::quick_stop_active}) {
    SCOPED_TRACE(to_string(s));
    Drive d = drive_in(s);
    d.update(fault_input());
    EXPECT_EQ(d.state(), State::fault_reaction_active);
    EXPECT_EQ(d.last_transition(), 13);
    d.update(fault_input(false));
    EXPECT_EQ(d.state(), State::fault_reaction_active) << "reacting until the motion stops";
    d.update(fault_input(true));
    EXPECT_EQ(d.state(), State::fault);
  }
}

TEST(CanopenCia402Drive, StaysWhereNoTransitionApplies) {
  struct Stay {
    State s;
    DriveInput in;
  };
  DriveConfig stay;
  stay.quick_stop_option = 6;
  const std::vector<Stay> cases = {
      {State::switch_on_disabled, cw(0x000F)},  // enable without shutdown first
      {State::switch_on_disabled, cw(0x0007)},
      {State::ready_to_switch_on, cw(0x0006)},
      {State::switched_on, cw(0x0007)},
      {State::operation_enabled, cw(0x000F)},
      {State::operation_enabled, cw(0x008F)},         // bit 7: no command outside fault
      {State::quick_stop_active, cw(0x0002, false)},  // ramp still running
      {State::quick_stop_active, cw(0x000F, false)},  // option 2: no way back to enabled
      {State::fault_reaction_active, fault_input(false)},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(to_string(c.s));
    Drive d = drive_in(c.s);
    d.update(c.in);
    EXPECT_EQ(d.state(), c.s);
  }
  Drive d = drive_in(State::quick_stop_active, stay);
  d.update(cw(0x0002, true));
  EXPECT_EQ(d.state(), State::quick_stop_active) << "options 5..8 stay after the stop";
}

TEST(CanopenCia402Drive, FaultResetNeedsAnEdgeAndNoFault) {
  Drive d = drive_in(State::fault);
  d.update(cw(0x0080));
  EXPECT_EQ(d.state(), State::switch_on_disabled) << "the edge from the 0x000F before";
  d = drive_in(State::fault);
  d.update({0x0000, true, true, true});
  d.update({0x0080, true, true, true});
  EXPECT_EQ(d.state(), State::fault) << "the fault is still there";
  d.update({0x0080, false, true, true});
  EXPECT_EQ(d.state(), State::fault) << "bit 7 held high is no edge";
  d.update(cw(0x0000));
  d.update(cw(0x0080));
  EXPECT_EQ(d.state(), State::switch_on_disabled);
}

TEST(CanopenCia402Drive, StatuswordCarriesVoltageRemoteAndExtraBits) {
  Drive d = drive_in(State::operation_enabled);
  d.set_status_bits(statusword::target_reached | statusword::switched_on);  // state bits are not extra
  EXPECT_EQ(d.statusword(), 0x0637);
  d.update({0x000F, false, true, false});
  EXPECT_EQ(d.statusword() & statusword::voltage_enabled, 0);
  EXPECT_TRUE(d.following());
  EXPECT_TRUE(d.powered());
}

// --- the controller against the drive model ----------------------------------------------

struct Loop {
  Controller controller;
  Drive drive;
  TimeNs now = 0;
  bool fault = false;
  bool standstill = true;
  std::vector<std::uint16_t> sent;
  ControllerOutput out;

  Loop(Drive d, ControllerConfig c = {}) : controller(c), drive(d) {}

  // Runs cycles until `until` holds or `max` cycles; returns the cycles run.
  template <class Until>
  int run(Until until, int max = 50) {
    for (int i = 0; i < max; ++i) {
      out = controller.update(drive.statusword(), now);
      sent.push_back(out.controlword);
      if (until(out)) return i + 1;
      drive.update({out.controlword, fault, standstill, true});
      now += ms;
    }
    return max;
  }
  int run_until_reached(int max = 50) {
    return run([](const ControllerOutput& o) { return o.progress == Progress::reached; }, max);
  }
};

TEST(CanopenCia402Controller, ReachesOperationEnabledFromEveryStartState) {
  DriveConfig stay;
  stay.quick_stop_option = 6;
  for (State start : {State::not_ready_to_switch_on, State::switch_on_disabled, State::ready_to_switch_on,
                      State::switched_on, State::operation_enabled, State::quick_stop_active}) {
    for (const DriveConfig& config : {DriveConfig{}, stay}) {
      if (start == State::quick_stop_active) continue;  // set up below, with a ramp running
      SCOPED_TRACE(to_string(start));
      Loop l(drive_in(start, config));
      l.controller.set_target(Target::operation_enabled, 0);
      const int cycles = l.run_until_reached();
      EXPECT_EQ(l.out.progress, Progress::reached);
      EXPECT_EQ(l.drive.state(), State::operation_enabled);
      EXPECT_LE(cycles, 6);
    }
  }
  for (const DriveConfig& config : {DriveConfig{}, stay}) {
    SCOPED_TRACE("quick stop active, option " + std::to_string(config.quick_stop_option));
    Loop l(drive_in(State::quick_stop_active, config));
    l.standstill = false;
    l.controller.set_target(Target::operation_enabled, 0);
    l.run_until_reached();
    EXPECT_EQ(l.drive.state(), State::operation_enabled);
  }
}

TEST(CanopenCia402Controller, ReachesOperationEnabledFromTheFaultStatesWithAReset) {
  for (State start : {State::fault_reaction_active, State::fault}) {
    SCOPED_TRACE(to_string(start));
    Loop l(drive_in(start));
    l.controller.set_target(Target::operation_enabled, 0);
    l.controller.request_fault_reset(0);
    l.run_until_reached();
    EXPECT_EQ(l.out.progress, Progress::reached);
    EXPECT_EQ(l.drive.state(), State::operation_enabled);
  }
}

TEST(CanopenCia402Controller, WalksShutdownSwitchOnEnableOperation) {
  Loop l(drive_in(State::switch_on_disabled));
  l.controller.set_target(Target::operation_enabled, 0);
  l.run_until_reached();
  EXPECT_EQ(l.sent, (std::vector<std::uint16_t>{0x0006, 0x0007, 0x000F, 0x000F}));
}

TEST(CanopenCia402Controller, ReachesEachTargetAndDisables) {
  for (Target t : {Target::ready_to_switch_on, Target::switched_on, Target::switch_on_disabled}) {
    SCOPED_TRACE(to_string(t));
    Loop l(drive_in(State::operation_enabled));
    l.controller.set_target(t, 0);
    l.run_until_reached();
    EXPECT_EQ(l.out.progress, Progress::reached);
  }
  Loop l(drive_in(State::operation_enabled));
  l.controller.set_target(Target::switch_on_disabled, 0);
  l.run_until_reached();
  EXPECT_EQ(l.sent.front(), 0x0000) << "disable voltage (transition 9)";
  EXPECT_EQ(l.drive.state(), State::switch_on_disabled);
}

TEST(CanopenCia402Controller, QuickStop) {
  {  // option 2: stop on the ramp, then switch on disabled
    Loop l(drive_in(State::operation_enabled));
    l.standstill = false;
    l.controller.set_target(Target::quick_stop, 0);
    l.run_until_reached();
    EXPECT_EQ(l.sent.front(), 0x0002);
    EXPECT_EQ(l.drive.state(), State::quick_stop_active);
    l.standstill = true;
    l.run([](const ControllerOutput& o) { return o.state == State::switch_on_disabled; });
    EXPECT_EQ(l.out.progress, Progress::reached) << "stopped and off is a finished quick stop";
  }
  {  // option 6: stays in quick stop active until enabled again
    DriveConfig stay;
    stay.quick_stop_option = 6;
    Loop l(drive_in(State::operation_enabled, stay));
    l.controller.set_target(Target::quick_stop, 0);
    l.run_until_reached();
    l.run([](const ControllerOutput&) { return false; }, 5);
    EXPECT_EQ(l.drive.state(), State::quick_stop_active);
    EXPECT_EQ(l.out.progress, Progress::reached);
    l.controller.set_target(Target::operation_enabled, l.now);
    l.run_until_reached();
    EXPECT_EQ(l.drive.state(), State::operation_enabled);
  }
}

TEST(CanopenCia402Controller, FaultAndFaultReset) {
  Loop l(drive_in(State::operation_enabled));
  l.controller.set_target(Target::operation_enabled, 0);
  l.run_until_reached();
  l.fault = true;
  l.standstill = false;
  l.run([](const ControllerOutput& o) { return o.state == State::fault_reaction_active; });
  EXPECT_EQ(l.out.progress, Progress::fault);
  l.standstill = true;
  l.run([](const ControllerOutput& o) { return o.state == State::fault; });
  EXPECT_EQ(l.out.progress, Progress::fault);
  EXPECT_EQ(l.out.controlword & controlword::fault_reset, 0) << "no reset unless asked";
  // Ten cycles in fault: the controller waits.
  l.run([](const ControllerOutput&) { return false; }, 10);
  EXPECT_EQ(l.drive.state(), State::fault);

  l.fault = false;  // the cause is gone
  l.controller.request_fault_reset(l.now);
  l.sent.clear();
  l.run_until_reached();
  EXPECT_EQ(l.drive.state(), State::operation_enabled);
  // The rising edge after a low bit 7, then the standard path up.
  EXPECT_EQ(l.sent, (std::vector<std::uint16_t>{0x0080, 0x0006, 0x0007, 0x000F, 0x000F}));
}

TEST(CanopenCia402Controller, RetriesTheResetEdgeABoundedNumberOfTimesThenReportsTheFault) {
  ControllerConfig c;
  c.transition_timeout = 1000 * ms;
  c.fault_reset_cycles = 4;
  c.fault_reset_tries = 3;
  Loop l(drive_in(State::fault), c);
  l.fault = true;  // the fault stays
  l.controller.set_target(Target::operation_enabled, 0);
  l.controller.request_fault_reset(0);
  l.run([](const ControllerOutput& o) { return o.progress != Progress::working; }, 100);
  EXPECT_EQ(l.out.progress, Progress::fault) << "given up: the fault stays";
  EXPECT_EQ(l.out.state, State::fault);
  EXPECT_EQ(l.out.fault_resets, 3);
  const auto edges = [&] {
    int n = 0;
    std::uint16_t previous = 0;
    for (const std::uint16_t cw : l.sent) {
      if ((cw & 0x80) && !(previous & 0x80)) ++n;
      previous = cw;
    }
    return n;
  };
  EXPECT_EQ(edges(), 3) << "an edge every fault_reset_cycles + 1 cycles, three times";
  l.run([](const ControllerOutput&) { return false; }, 30);
  EXPECT_EQ(edges(), 3) << "no more edges once given up";
  EXPECT_EQ(l.out.progress, Progress::fault);
  l.fault = false;  // cleared at last: a new request resets it
  l.controller.request_fault_reset(l.now);
  l.run_until_reached();
  EXPECT_EQ(l.drive.state(), State::operation_enabled);
}

TEST(CanopenCia402Controller, ReportsATransitionThatDoesNotHappen) {
  ControllerConfig c;
  c.transition_timeout = 100 * ms;
  Controller ctrl(c);
  ctrl.set_target(Target::operation_enabled, 0);
  ControllerOutput o;
  for (TimeNs t = 0; t < 100 * ms; t += ms) {
    o = ctrl.update(0x0250, t);  // a drive stuck in switch on disabled
    ASSERT_EQ(o.progress, Progress::working) << t;
  }
  o = ctrl.update(0x0250, 100 * ms);
  EXPECT_EQ(o.progress, Progress::timeout);
  EXPECT_EQ(o.state, State::switch_on_disabled);
  EXPECT_EQ(o.in_state_for, 100 * ms);
  EXPECT_EQ(o.controlword, 0x0006) << "still asking";
  o = ctrl.update(0x0231, 101 * ms);  // it moves: the clock restarts
  EXPECT_EQ(o.progress, Progress::working);
  EXPECT_EQ(o.in_state_for, 0);
}

TEST(CanopenCia402Controller, HoldsTheControlwordOnAnUnknownStatusword) {
  Controller ctrl;
  ctrl.set_target(Target::operation_enabled, 0);
  EXPECT_EQ(ctrl.update(0x0231, 0).controlword, 0x0007);
  const auto o = ctrl.update(0x0001, ms);
  EXPECT_EQ(o.progress, Progress::unknown_state);
  EXPECT_EQ(o.controlword, 0x0007);
}

TEST(CanopenCia402Controller, AddsOnlyModeBits) {
  Controller ctrl;
  ctrl.set_target(Target::operation_enabled, 0);
  ctrl.set_mode_bits(controlword::halt | 0x0001 | 0x0080);
  EXPECT_EQ(ctrl.update(0x0637, 0).controlword, 0x010F);
}

// --- units ----------------------------------------------------------------------------------

TEST(CanopenUnits, RotaryAxisThroughEncoderAndGear) {
  const DriveUnits u = DriveUnits::rotary(4096, 100, 0.5);
  std::int32_t counts = 0;
  ASSERT_EQ(u.position_to_counts(1.0, counts), Codec::ok);
  EXPECT_EQ(counts, 65190);  // 4096 * 100 / 2π
  EXPECT_NEAR(u.counts_to_position(counts), 1.0, 1e-4);
  ASSERT_EQ(u.velocity_to_counts(-2 * std::numbers::pi, counts), Codec::ok);
  EXPECT_EQ(counts, -409600);
  EXPECT_DOUBLE_EQ(u.counts_to_velocity(409600), 2 * std::numbers::pi);
  EXPECT_EQ(u.position_to_counts(1e6, counts), Codec::too_high);
  EXPECT_EQ(u.position_to_counts(-1e6, counts), Codec::too_low);
  EXPECT_EQ(u.position_to_counts(NAN, counts), Codec::invalid);
  EXPECT_EQ(u.velocity_to_counts(INFINITY, counts), Codec::invalid);
}

TEST(CanopenUnits, LinearAxisThroughALead) {
  const DriveUnits u = DriveUnits::linear(4096, 1, 0.005, 0.2);
  std::int32_t counts = 0;
  ASSERT_EQ(u.position_to_counts(0.001, counts), Codec::ok);
  EXPECT_EQ(counts, 819);  // 0.001 m / 5 mm per turn * 4096
  EXPECT_NEAR(u.counts_to_position(8192), 0.010, 1e-12);
}

TEST(CanopenUnits, TorqueInPerMilleOfRated) {
  const DriveUnits u = DriveUnits::rotary(4096, 1, 0.5);
  std::int16_t pm = 0;
  ASSERT_EQ(u.torque_to_per_mille(0.25, pm), Codec::ok);
  EXPECT_EQ(pm, 500);
  ASSERT_EQ(u.torque_to_per_mille(-0.5, pm), Codec::ok);
  EXPECT_EQ(pm, -1000);
  EXPECT_DOUBLE_EQ(u.per_mille_to_torque(1500), 0.75);
  EXPECT_EQ(u.torque_to_per_mille(20, pm), Codec::too_high);  // 40000 ‰
  EXPECT_EQ(u.torque_to_per_mille(-20, pm), Codec::too_low);
  EXPECT_EQ(u.torque_to_per_mille(NAN, pm), Codec::invalid);
}

TEST(CanopenUnits, RefusesNonsenseFactors) {
  EXPECT_THROW(DriveUnits::rotary(0, 1, 1), std::invalid_argument);
  EXPECT_THROW(DriveUnits::rotary(4096, -1, 1), std::invalid_argument);
  EXPECT_THROW(DriveUnits::rotary(4096, 1, NAN), std::invalid_argument);
  EXPECT_THROW(DriveUnits::linear(4096, 1, 0, 1), std::invalid_argument);
  const DriveUnits unset;
  std::int32_t counts = 7;
  std::int16_t pm = 7;
  EXPECT_EQ(unset.position_to_counts(1.0, counts), Codec::invalid) << "never 0 counts by default";
  EXPECT_EQ(unset.torque_to_per_mille(1.0, pm), Codec::invalid);
  EXPECT_EQ(counts, 7);
}

}  // namespace
