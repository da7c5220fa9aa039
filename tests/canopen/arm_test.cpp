// CanopenArm against in-process drives: enable, CSP following, servo_cf through Jᵀ in CST,
// refused commands, the watchdog, and every fault with its reason and the recovery from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "arm_rig.hpp"
#include "saw/log.hpp"

namespace {

using namespace saw::canopen;
using namespace saw::canopen::test;
using saw::FaultCode;
using saw::FaultInfo;
using saw::JointState;
using saw::OperatingStateValue;
using saw::StateCommand;
using saw::TimeNs;
using saw::Wrench;
namespace can = saw::can;

constexpr double count = 2 * M_PI / 4096;  // one encoder count, in rad

TEST(CanopenArm, EnableWalksEveryDriveToOperationEnabled) {
  ArmRig rig(arm_config(cia402::csp));
  rig.cycle(5);
  EXPECT_EQ(rig.state(), OperatingStateValue::disabled);
  EXPECT_EQ(rig.drives[0].state(), cia402::State::switch_on_disabled);
  rig.state_command(StateCommand::enable);
  rig.cycle();
  EXPECT_TRUE(rig.arm->operating_state().is_busy) << "busy while the drives walk up";
  const int took = rig.cycle_until([&] { return rig.state() == OperatingStateValue::enabled; });
  EXPECT_LT(took, 10);
  EXPECT_FALSE(rig.arm->operating_state().is_busy);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(rig.drives[i].state(), cia402::State::operation_enabled) << i;
  const JointState js = rig.read<JointState>("measured_js");
  EXPECT_EQ(js.size, 3u);
  EXPECT_EQ(js.name_of(1), "shoulder_pitch");
  rig.state_command(StateCommand::disable);
  rig.cycle(5);
  EXPECT_EQ(rig.state(), OperatingStateValue::disabled);
  EXPECT_EQ(rig.drives[2].state(), cia402::State::switch_on_disabled);
}

TEST(CanopenArm, CspFollowsServoJp) {
  TestDriveConfig start;
  start.initial_position = 300;  // the drives start away from zero: enabling must not jump
  ArmRig rig(arm_config(cia402::csp), start);
  rig.enable();
  EXPECT_EQ(rig.drives[0].target_position(), 300) << "the target tracked the drive while enabling";
  const double q0 = 300 * count;
  for (int i = 0; i < 300; ++i) {
    const double d = 0.3 * std::sin(i * 0.01);
    rig.write("servo_jp", rig.joints(q0 + d, q0 - d, q0 + 0.5 * d));
    rig.cycle();
  }
  const double d = 0.3 * std::sin(299 * 0.01);
  EXPECT_NEAR(rig.drives[0].position() * count, q0 + d, 1.5 * count);
  EXPECT_NEAR(rig.drives[1].position() * count, q0 - d, 1.5 * count);
  const JointState s = rig.read<JointState>("setpoint_js");
  EXPECT_NEAR(s.position[0], q0 + d, 1e-12);
  rig.cycle();
  const JointState m = rig.read<JointState>("measured_js");
  EXPECT_NEAR(m.position[2], q0 + 0.5 * d, 1.5 * count);
  EXPECT_EQ(rig.arm->device_status().refused.total(), 0u);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
}

TEST(CanopenArm, JointOffsetsShiftPositionsBothWays) {
  CanopenArmConfig c = arm_config(cia402::csp);
  c.joints[2].offset = 1.2;  // the elbow drive's zero is the joint's 1.2 rad
  ArmRig rig(c);
  rig.enable();
  rig.cycle();
  EXPECT_NEAR(rig.read<JointState>("measured_js").position[2], 1.2, 1e-12);
  rig.write("servo_jp", rig.joints(0, 0, 1.21));
  rig.cycle();
  EXPECT_EQ(rig.drives[2].target_position(), std::lround(0.01 / count)) << "the drive gets 0.01 rad";
  rig.cycle();
  EXPECT_NEAR(rig.read<JointState>("measured_js").position[2], 1.21, count);
  EXPECT_NEAR(rig.read<saw::Pose>("measured_cp").position[2], -0.133 * std::sin(1.21), 1e-3);
}

TEST(CanopenArm, ServoCfBecomesJointTorquesThroughTheJacobianTranspose) {
  ArmRig rig(arm_config(cia402::cst));
  rig.enable();
  rig.cycle(2);
  const saw::Pose p = rig.read<saw::Pose>("measured_cp");
  EXPECT_NEAR(p.position[0], 0.266, 1e-9) << "straight arm along x";
  const Wrench w{{0.0, 0.5, -1.0}, {0, 0, 0}};
  rig.write("servo_cf", w);
  rig.cycle();
  // τ = Jᵀf, each column of J from the forward kinematics by finite differences.
  ChainKinematics k(omni_chain());
  const JointState js = rig.read<JointState>("measured_js");
  for (std::size_t i = 0; i < 3; ++i) {
    std::array<double, 3> plus{js.position[0], js.position[1], js.position[2]}, minus = plus;
    plus[i] += 1e-6;
    minus[i] -= 1e-6;
    const auto a = k.fk(plus).position, b = k.fk(minus).position;
    double tau = 0;
    for (int r = 0; r < 3; ++r) tau += (a[r] - b[r]) / 2e-6 * w.force[r];
    EXPECT_NEAR(rig.drives[i].target_torque(), tau / 0.5 * 1000, 1.0) << "joint " << i;
  }
  EXPECT_NE(rig.drives[0].target_torque(), 0) << "a force along y turns the base";
  EXPECT_EQ(rig.drives[1].target_torque(), static_cast<std::int16_t>(std::lround(0.266 * 1.0 / 0.5 * 1000)))
      << "1 N down at 0.266 m from the shoulder";
  // Beyond the joints' torque (0.5 N·m rated): refused, zero torque.
  rig.write("servo_cf", Wrench{{0.0, 0.0, -2.0}, {0, 0, 0}});
  rig.cycle();
  EXPECT_EQ(rig.drives[1].target_torque(), 0);
  EXPECT_EQ(rig.arm->device_status().refused.over_limit, 1u);
}

TEST(CanopenArm, NonFiniteAndOutOfRangeCommandsAreRefusedCountedAndNeverSent) {
  ArmRig rig(arm_config(cia402::csp));
  rig.enable();
  rig.write("servo_jp", rig.joints(0.01, 0, 0));
  rig.cycle(2);
  const std::int32_t held = rig.drives[0].target_position();
  EXPECT_EQ(held, std::lround(0.01 / count));
  rig.write("servo_jp", rig.joints(std::nan(""), 0, 0));
  rig.cycle();
  rig.write("servo_jp", rig.joints(0.01, INFINITY, 0));
  rig.cycle();
  rig.write("servo_jp", rig.joints(2.5, 0, 0));  // beyond max
  rig.cycle();
  rig.write("servo_jp", rig.joints(0.5, 0, 0));  // a 0.49 rad step in 1 ms: 490 rad/s
  rig.cycle();
  JointState two = rig.joints(0.01, 0, 0);
  two.size = 2;
  rig.write("servo_jp", two);
  rig.cycle();
  rig.write("servo_jf", rig.joints(0.1, 0, 0));  // a torque to a position-mode arm
  rig.cycle();
  const RefusedCommands r = rig.arm->device_status().refused;
  EXPECT_EQ(r.not_finite, 2u);
  EXPECT_EQ(r.over_limit, 2u);
  EXPECT_EQ(r.wrong_size, 1u);
  EXPECT_EQ(r.wrong_mode, 1u);
  EXPECT_EQ(rig.drives[0].target_position(), held) << "the drive was held where it was";
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled) << "a refused command is not a fault";
  // In torque mode a refused command is zero torque at once.
  ArmRig cst(arm_config(cia402::cst));
  cst.enable();
  cst.write("servo_jf", cst.joints(0.2, 0, 0));
  cst.cycle();
  EXPECT_EQ(cst.drives[0].target_torque(), 400);
  cst.write("servo_jf", cst.joints(std::nan(""), 0, 0));
  cst.cycle();
  EXPECT_EQ(cst.drives[0].target_torque(), 0);
  cst.write("servo_jf", cst.joints(0.6, 0, 0));  // above the rated 0.5 N·m
  cst.cycle();
  EXPECT_EQ(cst.drives[0].target_torque(), 0);
  cst.write("servo_cf", Wrench{{NAN, 0, 0}, {0, 0, 0}});
  cst.cycle();
  EXPECT_EQ(cst.drives[1].target_torque(), 0);
  EXPECT_EQ(cst.arm->device_status().refused.total(), 3u);
}

TEST(CanopenArm, TheWatchdogHoldsAndReportsWhenCommandsStop) {
  ArmRig rig(arm_config(cia402::cst));
  rig.enable();
  for (int i = 0; i < 10; ++i) {
    rig.write("servo_jf", rig.joints(0.1, 0.1, 0.1));
    rig.cycle();
  }
  EXPECT_EQ(rig.drives[0].target_torque(), 200);
  rig.cycle(5);  // command_timeout: 5 ms
  EXPECT_EQ(rig.drives[0].target_torque(), 200) << "not yet";
  rig.cycle(2);
  EXPECT_EQ(rig.drives[0].target_torque(), 0) << "zero torque";
  EXPECT_TRUE(rig.read<bool>("command_timeout"));
  EXPECT_EQ(rig.read<std::uint64_t>("watchdog_trips"), 1u);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled) << "on_command_timeout: hold";
  rig.write("servo_jf", rig.joints(0.1, 0.1, 0.1));
  rig.cycle(2);
  EXPECT_EQ(rig.drives[0].target_torque(), 200) << "a fresh command drives again";
  EXPECT_FALSE(rig.read<bool>("command_timeout"));

  CanopenArmConfig c = arm_config(cia402::csp);
  c.contract.fault_on_command_timeout = true;
  ArmRig faulting(c);
  faulting.enable();
  faulting.write("servo_jp", faulting.joints(0.001, 0, 0));
  faulting.cycle(10);
  EXPECT_EQ(faulting.state(), OperatingStateValue::fault);
  EXPECT_EQ(faulting.arm->fault_reason(), FaultReason::command_stale);
  EXPECT_EQ(faulting.arm->fault().code, FaultCode::input_stale);
}

TEST(CanopenArm, ALostHeartbeatFaultsWithinTheHeartbeatTimeoutNamingTheJoint) {
  ArmRig rig(arm_config(cia402::cst));
  rig.enable();
  rig.write("servo_jf", rig.joints(0.1, 0.1, 0.1));
  rig.drives[1].set_heartbeat_silent(true);
  const TimeNs silent_at = rig.now;
  const int took = rig.cycle_until([&] {
    rig.write("servo_jf", rig.joints(0.1, 0.1, 0.1));
    return rig.state() == OperatingStateValue::fault;
  });
  EXPECT_LE(took * ms, 31 * ms) << "within heartbeat_timeout (30 ms) of the last heartbeat";
  EXPECT_GE(rig.now - silent_at, 20 * ms) << "and not before it";
  const FaultInfo f = rig.read<FaultInfo>("fault");
  EXPECT_EQ(f.code, FaultCode::device_lost);
  EXPECT_EQ(f.source_name(), "shoulder_pitch");
  EXPECT_GE(f.age_ns, 30 * ms);
  EXPECT_EQ(rig.arm->fault_reason(), FaultReason::heartbeat_lost);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_EQ(rig.drives[i].target_torque(), 0) << "zero torque on every joint: " << i;
  EXPECT_EQ(rig.drives[0].state(), cia402::State::quick_stop_active);
  rig.cycle(3);
  EXPECT_EQ(rig.drives[0].state(), cia402::State::switch_on_disabled) << "quick stopped";

  // Silent altogether: its TPDOs stop first, then the fault says the node is gone.
  ArmRig gone(arm_config(cia402::cst));
  gone.enable();
  gone.drives[2].set_silent(true);
  gone.cycle_until([&] { return gone.state() == OperatingStateValue::fault; });
  EXPECT_EQ(gone.arm->fault_reason(), FaultReason::feedback_stale);
  gone.cycle(40);
  EXPECT_EQ(gone.arm->fault_reason(), FaultReason::heartbeat_lost);
  EXPECT_EQ(gone.arm->fault().source_name(), "elbow_pitch");
}

TEST(CanopenArm, ADriveFaultAndItsEmcyFaultTheArmByName) {
  ArmRig rig(arm_config(cia402::csp));
  rig.enable();
  rig.drives[2].raise_fault(0x2310);
  rig.cycle_until([&] { return rig.state() == OperatingStateValue::fault; }, 10);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.arm->fault_reason(), FaultReason::emcy);
  EXPECT_EQ(rig.arm->fault().code, FaultCode::device_error);
  EXPECT_EQ(rig.arm->fault().detail, 0x2310u);
  EXPECT_EQ(rig.arm->fault().source_name(), "elbow_pitch");
  EXPECT_STREQ(emcy_name(0x2310).data(), "continuous over-current (device output side)");
  rig.cycle(5);
  EXPECT_EQ(rig.drives[2].state(), cia402::State::fault);
  EXPECT_EQ(rig.drives[0].state(), cia402::State::switch_on_disabled) << "the others quick-stopped";

  // The statusword alone (a drive whose EMCY was lost): drive fault, with the last EMCY code.
  ArmRig quiet(arm_config(cia402::csp));
  quiet.enable();
  quiet.drives[1].raise_fault(0x8611);
  // Drop the EMCY on the way: only the statusword tells.
  quiet.drives[1].step(quiet.now);  // the EMCY goes out now ...
  can::Received discard[64];
  (void)quiet.port.receive(discard);  // ... and is lost
  quiet.cycle_until([&] { return quiet.state() == OperatingStateValue::fault; }, 10);
  EXPECT_EQ(quiet.arm->fault_reason(), FaultReason::drive_fault);
  EXPECT_EQ(quiet.arm->fault().source_name(), "shoulder_pitch");
}

TEST(CanopenArm, BusOffFaults) {
  ArmRig rig(arm_config(cia402::cst));
  rig.enable();
  rig.network.state = can::BusState::bus_off;
  rig.cycle();
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.arm->fault_reason(), FaultReason::bus_off);
  EXPECT_EQ(rig.arm->fault().code, FaultCode::device_lost);
  EXPECT_EQ(rig.arm->fault().source_name(), "bus");
  EXPECT_EQ(rig.arm->fault().detail, static_cast<std::uint32_t>(can::BusState::bus_off));
  EXPECT_EQ(rig.arm->status().bus_state, static_cast<std::uint8_t>(can::BusState::bus_off));
  // Still off: enable faults again at once.
  rig.state_command(StateCommand::enable);
  rig.cycle();
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  // Back on: the drives had quick-stopped or gone silent for a moment; enable recovers.
  rig.network.state = can::BusState::error_active;
  rig.enable();
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
}

TEST(CanopenArm, EnableRecoversAfterTheFaultIsReset) {
  ArmRig rig(arm_config(cia402::cst));
  rig.enable();
  rig.drives[0].raise_fault(0x4310);
  rig.cycle(10);
  ASSERT_EQ(rig.state(), OperatingStateValue::fault);
  // The condition gone, enable resets the drive's fault and walks every drive up again.
  rig.drives[0].clear_fault();
  rig.state_command(StateCommand::enable);
  const int took = rig.cycle_until([&] { return rig.state() == OperatingStateValue::enabled; }, 100);
  EXPECT_LT(took, 30);
  EXPECT_EQ(rig.drives[0].state(), cia402::State::operation_enabled);
  EXPECT_EQ(rig.arm->fault().code, FaultCode::none) << "cleared by enable";
  EXPECT_EQ(rig.arm->status().faults, 1u);
  EXPECT_EQ(rig.arm->status().fault.detail, 0x4310u) << "the status keeps the last fault";
  rig.write("servo_jf", rig.joints(0.05, 0, 0));
  rig.cycle(2);
  EXPECT_EQ(rig.drives[0].target_torque(), 100);

  // A heartbeat that comes back: enable recovers too.
  rig.drives[1].set_heartbeat_silent(true);
  rig.cycle(40);
  ASSERT_EQ(rig.arm->fault_reason(), FaultReason::heartbeat_lost);
  rig.state_command(StateCommand::enable);
  rig.cycle(3);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault) << "still silent: faults again";
  rig.drives[1].set_heartbeat_silent(false);
  rig.cycle(12);
  rig.enable();
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
}

TEST(CanopenArm, AFaultThatPersistsEndsTheEnableInAFaultNamingItsErrorCode) {
  CanopenArmConfig c = arm_config(cia402::csp);
  c.transition_timeout = 500 * ms;
  ArmRig rig(c);
  rig.enable();
  rig.drives[1].raise_fault(0x5000);
  rig.cycle(5);
  rig.state_command(StateCommand::enable);  // the fault condition is still there
  bool said_enabled = false, said_busy = false;
  rig.cycle_until(
      [&] {
        said_enabled = said_enabled || rig.state() == OperatingStateValue::enabled;
        said_busy = said_busy || rig.arm->operating_state().is_busy;
        return rig.arm->fault_reason() == FaultReason::drive_fault;
      },
      200);
  EXPECT_FALSE(said_enabled) << "a client (the teleoperation) waits while the drives are walked up";
  EXPECT_TRUE(said_busy);
  // Three reset edges (the default), then the fault with the drive's error code (0x603F).
  EXPECT_EQ(rig.arm->fault_reason(), FaultReason::drive_fault);
  EXPECT_EQ(rig.arm->fault().source_name(), "shoulder_pitch");
  EXPECT_EQ(rig.arm->fault().detail, 0x5000u);
  EXPECT_EQ(rig.arm->status().fault_node, rig.arm->arm_config().joints[1].node);
  EXPECT_EQ(rig.arm->master().control(1).fault_resets, 3);
}

// A boot-up while an enable runs: the enable configures the drive again and goes on (no FAULT),
// and the log says that the drive rebooted.
TEST(CanopenArm, ADriveThatRebootsDuringAnEnableIsConfiguredAgainAndLogged) {
  saw::LogRecord r;
  while (saw::log_ring().pop(r)) {
  }
  ArmRig rig(arm_config(cia402::csp));
  rig.state_command(StateCommand::enable);
  rig.cycle(3);
  ASSERT_TRUE(rig.arm->enabling());
  const std::size_t before = rig.drives[1].writes().size();
  rig.drives[1].reboot();
  rig.cycle_until([&] { return rig.state() == OperatingStateValue::enabled; }, 2000);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  EXPECT_EQ(rig.arm->status().faults, 0u);
  EXPECT_GT(rig.drives[1].writes().size(), before) << "configured again";
  EXPECT_EQ(rig.drives[1].state(), cia402::State::operation_enabled);
  bool logged = false;
  while (saw::log_ring().pop(r))
    logged = logged || saw::format_log_record(r).find(
                           "shoulder_pitch (node 2) rebooted (boot-up seen) during the "
                           "enable: configuring it again") != std::string::npos;
  EXPECT_TRUE(logged);
}

TEST(CanopenArm, ADriveThatRebootedFaultsAndTheNextEnableConfiguresItAgain) {
  ArmRig rig(arm_config(cia402::csp));
  rig.enable();
  ASSERT_EQ(rig.state(), OperatingStateValue::enabled);
  rig.drives[1].reboot();  // its PDOs, heartbeat and mode are gone
  rig.cycle_until([&] { return rig.state() == OperatingStateValue::fault; }, 50);
  EXPECT_EQ(rig.arm->fault_reason(), FaultReason::node_rebooted);
  EXPECT_EQ(rig.arm->fault().source_name(), "shoulder_pitch");
  EXPECT_EQ(rig.drives[1].nmt_state(), NmtState::pre_operational);
  rig.cycle(20);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault) << "it stays faulted until an enable";

  const std::size_t before = rig.drives[1].writes().size();
  rig.state_command(StateCommand::enable);
  rig.cycle_until([&] { return rig.state() == OperatingStateValue::enabled; }, 2000);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  EXPECT_EQ(rig.drives[1].nmt_state(), NmtState::operational);
  EXPECT_EQ(rig.drives[1].state(), cia402::State::operation_enabled);
  // The start-up's writes again: the PDOs, 0x1017, 0x1016, 0x6007, 0x6060.
  const auto& w = rig.drives[1].writes();
  const auto written = [&](ObjectAddress a) {
    return std::any_of(w.begin() + static_cast<std::ptrdiff_t>(before), w.end(),
                       [&](const TestDrive::Write& x) { return x.address == a; });
  };
  EXPECT_TRUE(written({0x1600, 1}));
  EXPECT_TRUE(written({0x1017, 0}));
  EXPECT_TRUE(written({0x1016, 1}));
  EXPECT_TRUE(written(cia402::object::modes_of_operation));
  rig.cycle(100);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled) << "its TPDOs and heartbeats came back";
  // The status keeps the last fault and its reason after the recovery (the run's summary says it).
  EXPECT_EQ(rig.arm->status().faults, 1u);
  EXPECT_EQ(rig.arm->status().reason, FaultReason::node_rebooted);
  EXPECT_EQ(rig.arm->status().fault.source_name(), "shoulder_pitch");
}

TEST(CanopenArm, AnEmcyWhoseDriveStaysOutOfFaultIsAWarning) {
  ArmRig rig(arm_config(cia402::csp));
  rig.enable();
  rig.drives[0].warn(0x4210, 0x09);
  rig.cycle(20);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  EXPECT_EQ(rig.arm->status().warnings, 1u);
  EXPECT_EQ(rig.arm->status().last_warning, 0x4210u);
  EXPECT_EQ(rig.arm->status().last_warning_register, 0x09u);
  EXPECT_EQ(rig.arm->status().last_warning_node, rig.arm->arm_config().joints[0].node);
}

TEST(CanopenArm, JointLimitsAndFollowingErrorFault) {
  ArmRig rig(arm_config(cia402::csv));
  rig.enable();
  int n = 0;
  rig.cycle_until([&] {
    rig.write("servo_jv", rig.joints(3.5, 0, 0));  // toward max (2 rad)
    return rig.state() == OperatingStateValue::fault || ++n > 2000;
  });
  EXPECT_EQ(rig.arm->fault_reason(), FaultReason::joint_limit);
  EXPECT_EQ(rig.arm->fault().code, FaultCode::limit_exceeded);
  EXPECT_EQ(rig.arm->fault().source_name(), "yaw");
  EXPECT_NEAR(rig.read<JointState>("measured_js").position[0], 2.0, 0.01);

  TestDriveConfig slow;
  slow.csp_max_step = 1;  // one count per ms: 1.5 rad/s
  ArmRig lag(arm_config(cia402::csp), slow);
  lag.enable();
  double q = 0;
  lag.cycle_until([&] {
    q += 0.0035;  // 3.5 rad/s, within max_velocity
    lag.write("servo_jp", lag.joints(0, q, 0));
    return lag.state() == OperatingStateValue::fault;
  });
  EXPECT_EQ(lag.arm->fault_reason(), FaultReason::following_error);
  EXPECT_EQ(lag.arm->fault().source_name(), "shoulder_pitch");
  EXPECT_NEAR(q, 0.2 / (1 - 1.5 / 3.5), 0.02) << "when the lag passed following_error (0.2 rad)";
}

TEST(CanopenArm, SdoReadsAndWritesFromANonRtThread) {
  ArmRig rig(arm_config(cia402::csp));
  rig.cycle(3);
  SdoRequest q;
  q.node = 2;
  q.index = 0x6502;
  SdoReply reply;
  std::atomic<bool> done{false};
  std::thread caller([&] {
    (void)rig.command("sdo", "canopen").read(&q, &reply);
    done.store(true, std::memory_order_release);
  });
  for (int i = 0; i < 5000 && !done.load(std::memory_order_acquire); ++i) {
    rig.cycle();
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  caller.join();
  EXPECT_TRUE(reply.ok()) << static_cast<int>(reply.status) << " " << reply.abort;
  EXPECT_EQ(reply.size, 4);
  EXPECT_EQ(reply.data[0], 0x80) << "csp's bit";
  EXPECT_EQ(reply.data[1], 0x03) << "csv's and cst's bits";
  EXPECT_EQ(rig.arm->status().sdo_done, 1u);
}

TEST(CanopenArm, SecondMasterOnABusIsRefused) {
  RingNetwork network;
  RingPort& port = network.attach("shared");
  const auto task = saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0);
  CanopenArm first("first", task, arm_config(cia402::csp, 1), port);
  try {
    CanopenArm second("second", task, arm_config(cia402::csp, 1), port);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("has a CANopen master in this process already ('first')"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace

// The in-test drive's heartbeat consumer (0x1016:01, written by the arm) when the arm dies: EMCY
// 0x8130, then what 0x6007 says, then pre-operational; the test drive is the arm rigs' hardware.
TEST(CanopenArm, WhenTheArmDiesEachDriveDoesWhatItsAbortConnectionOptionSays) {
  const std::pair<AbortConnection, saw::canopen::cia402::State> cases[] = {
      {AbortConnection::fault, saw::canopen::cia402::State::fault},
      {AbortConnection::disable_voltage, saw::canopen::cia402::State::switch_on_disabled},
      {AbortConnection::quick_stop, saw::canopen::cia402::State::switch_on_disabled},  // 0x605A: 2
      {AbortConnection::none, saw::canopen::cia402::State::operation_enabled}};
  for (const auto& [option, expected] : cases) {
    auto c = arm_config(saw::canopen::cia402::csp);
    c.abort_connection = option;
    c.rpdo_deadline = 0;  // the heartbeat consumer alone (the RPDO deadline: rpdo_deadline_test.cpp)
    ArmRig rig(c);
    rig.enable();
    ASSERT_EQ(rig.state(), OperatingStateValue::enabled);
    RingPort& spy = rig.network.attach("spy");
    for (int i = 0; i < 1000; ++i, rig.now += saw::canopen::test::ms)
      rig.drives.step(rig.now);  // the arm is dead
    int emcy_8130 = 0;
    can::Received rx[64];
    for (std::size_t n; (n = spy.receive(rx)) > 0;)
      for (std::size_t k = 0; k < n; ++k) {
        const can::Frame& f = rx[k].frame;
        emcy_8130 += f.can_id() == 0x81 && f.len == 8 && f.data[0] == 0x30 && f.data[1] == 0x81;
      }
    const auto n = static_cast<int>(option);
    EXPECT_EQ(emcy_8130, 1) << "option " << n;
    EXPECT_EQ(rig.drives[0].heartbeat_events(), 1u) << "option " << n;
    EXPECT_EQ(rig.drives[0].state(), expected) << "option " << n;
    EXPECT_EQ(rig.drives[0].nmt_state(), NmtState::pre_operational) << "option " << n;
  }
}
