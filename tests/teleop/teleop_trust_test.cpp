// The teleoperation task trusts no input: non-finite rows, overflowing positions, settings
// beyond their bounds, queued commands combined in one cycle, a dead source behind a delay.
// Every FAULT says why. All on the stepped clock.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>

#include "saw/detail/access.hpp"
#include "saw/log.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/stepper.hpp"
#include "saw/testing/teleop_rig.hpp"
#include "teleop_support.hpp"

namespace {

using namespace std::chrono_literals;
using saw::OperatingStateValue;
using saw::Status;
using saw::teleop::FaultCode;
using saw::teleop::FaultInfo;
using saw::testing::basic;
using saw::testing::norm;
using saw::testing::Rig;
using saw::testing::TeleopConfig;

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr double inf = std::numeric_limits<double>::infinity();

bool finite(const saw::Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

TEST(TeleopTrust, SaturateIsNanSafe) {
  using saw::teleop::saturate;
  EXPECT_TRUE(saturate(Eigen::Vector3d(nan, 0, 0), 3).isZero());
  EXPECT_TRUE(saturate(Eigen::Vector3d(inf, 1, 0), 3).isZero());
  EXPECT_TRUE(saturate(Eigen::Vector3d(1e308, 1e308, 0), 3).isZero()) << "the norm overflows";
  EXPECT_TRUE(saturate(Eigen::Vector3d(1, 0, 0), nan).isZero());
  EXPECT_TRUE(saturate(Eigen::Vector3d(4, 0, 0), 2).isApprox(Eigen::Vector3d(2, 0, 0)));
}

// NaN and infinite rows are failed reads: the last good value (and its force) holds, finite,
// and FAULT with zero force follows once the last good value is older than stale_timeout.
TEST(TeleopTrust, NonFiniteInputIsAFailedReadThenAFault) {
  for (const double bad : {nan, inf, -inf}) {
    for (const bool velocity : {false, true}) {
      SCOPED_TRACE(std::to_string(bad) + (velocity ? " velocity" : " position"));
      TeleopConfig c = basic();
      c.stale_timeout = 0.005;
      Rig rig(c);
      rig.step(3);
      rig.master.position[0] += 0.01;
      rig.step(1);
      const saw::Vec3 held = rig.slave.force;
      ASSERT_NEAR(held[0], 1.0, 1e-9);
      (velocity ? rig.master.velocity : rig.master.position)[1] = bad;
      for (int i = 0; i < 5; ++i) {  // 5 ms: the last good value still holds
        rig.step(1);
        ASSERT_TRUE(finite(rig.slave.force) && finite(rig.master.force));
        EXPECT_EQ(rig.slave.force, held);
        EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
      }
      rig.step(2);
      EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::fault);
      EXPECT_EQ(rig.teleop.fault().code, FaultCode::input_not_finite);
      EXPECT_EQ(rig.teleop.fault().source_name(), "master");
      EXPECT_EQ(norm(rig.slave.force), 0.0);
      EXPECT_EQ(norm(rig.master.force), 0.0);
      EXPECT_GE(rig.teleop.rejected_inputs(), 6u);
    }
  }
}

// A NaN on the cycle that snaps the offset (enable) or re-expresses it (rescale) must not stick
// in the Ruckig offset: once the inputs are good again, so is everything.
TEST(TeleopTrust, ANanOnASnapOrRescaleCycleDoesNotStick) {
  for (const bool rescale : {false, true}) {
    SCOPED_TRACE(rescale ? "rescale" : "snap");
    TeleopConfig c = basic();
    c.start_enabled = rescale;
    c.stale_timeout = 0.005;
    Rig rig(c);
    rig.step(3);
    rig.master.position = {nan, 0, 0};
    ASSERT_EQ(rescale ? rig.op.set_scale(2.0) : rig.op.state_command(saw::StateCommand::enable), Status::ok);
    rig.step(2);
    rig.master.position = {0.02, 0, 0};
    rig.step(2);
    EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
    saw::Vec3 offset{};
    ASSERT_EQ(rig.teleop.state_table().read_latest(rig.teleop.columns().slave_offset, offset), Status::ok);
    EXPECT_TRUE(finite(offset));
    ASSERT_TRUE(finite(rig.slave.force));
    rig.master.position[0] += 0.01;  // teleoperation goes on
    rig.step(1);
    EXPECT_GT(norm(rig.slave.force), 0.1);
    EXPECT_TRUE(finite(rig.slave.force));
  }
}

// A finite position large enough to overflow the law: the force check before sending catches
// it (zero force, FAULT saying which check).
TEST(TeleopTrust, AForceThatIsNotFiniteIsNeverSent) {
  Rig rig(basic());
  rig.step(3);
  rig.master.position = {1.7e308, 0, 0};
  rig.step(1);
  EXPECT_TRUE(finite(rig.slave.force) && finite(rig.master.force));
  EXPECT_EQ(norm(rig.slave.force), 0.0);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, FaultCode::output_not_finite);
}

TEST(TeleopTrust, GainsScaleAndLimitsHaveUpperBounds) {
  using namespace saw::teleop;
  Rig rig(basic());
  ASSERT_EQ(rig.op.set_gains({max_gain * 1.01, 100}), Status::ok);
  ASSERT_EQ(rig.op.set_gains({100, 1e300}), Status::ok);
  ASSERT_EQ(rig.op.set_scale(max_scale * 1.01), Status::ok);
  ASSERT_EQ(rig.op.set_scale(min_scale * 0.99), Status::ok);
  ASSERT_EQ(rig.op.set_force_limits({max_force_limit * 1.01, 3}), Status::ok);
  ASSERT_EQ(rig.op.set_prediction({true, max_horizon * 1.01, 0}), Status::ok);
  rig.step(2);
  EXPECT_EQ(rig.teleop.rejected_commands(), 6u);
  ASSERT_EQ(rig.op.set_gains({max_gain, max_gain}), Status::ok);  // the bounds themselves are fine
  ASSERT_EQ(rig.op.set_scale(max_scale), Status::ok);
  rig.step(1);
  EXPECT_EQ(rig.teleop.rejected_commands(), 6u);
}

TEST(TeleopTrust, RuckigRefusalsAreCountedAndVisible) {
  Rig rig(basic());
  rig.step(3);
  EXPECT_EQ(rig.teleop.offset_errors(), 0u);
  // 1000 km at 5 cm/s: beyond what Ruckig plans (its duration limit), so it refuses.
  ASSERT_EQ(rig.op.set_slave_offset({1e6, 0, 0}), Status::ok);
  rig.step(3);
  EXPECT_GE(rig.teleop.offset_errors(), 1u);
  std::uint64_t column = 0;
  ASSERT_EQ(rig.teleop.state_table().read_latest(rig.teleop.columns().offset_errors, column), Status::ok);
  EXPECT_EQ(column, rig.teleop.offset_errors());
  EXPECT_TRUE(finite(rig.slave.force));
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled) << "refused: the offset stays put";
}

// The case of the issue: scale 1 → 2 queued with enable, p_m = (0.05, 0.02, 0), k = 300.
TEST(TeleopTrust, EnableWithSetScaleInOneCycleAppliesTheRescaleOnce) {
  for (const auto state : {saw::StateCommand::enable, saw::StateCommand::resume}) {
    SCOPED_TRACE(std::string(saw::to_string(state)));
    TeleopConfig c = basic();
    c.gains = {300, 300};
    Rig rig(c);
    rig.master.position = {0.05, 0.02, 0};
    rig.step(3);
    if (state == saw::StateCommand::resume) {
      ASSERT_EQ(rig.op.state_command(saw::StateCommand::pause), Status::ok);
      rig.step(2);
    }
    ASSERT_EQ(rig.op.state_command(state), Status::ok);
    ASSERT_EQ(rig.op.set_scale(2.0), Status::ok);
    rig.step(1);
    EXPECT_LT(norm(rig.slave.force), 1e-9);
    EXPECT_LT(norm(rig.master.force), 1e-9);
  }
}

// ---- Every ordered pair of commands queued in one cycle, from every state --------------------
//
// With the devices held still, a command may change the force only as far as its new gains,
// limits or scale imply. Engaged (enabled, clutch released) before and after the cycle, the slave
// error e_s is kept: a scale or prediction change re-expresses the offset, a new offset target
// is reached along a jerk-limited path. It may vanish only if the cycle disengaged and
// re-engaged (pause, disable or clutch, then resume, enable or release: the offset re-aligns, as
// it does over two cycles). Engaging starts from zero error; disengaged, the forces are zero.
// The forces follow: |f_s'| ≤ min(lim_s', k_s'·|e_s|), |f_m'| ≤ min(lim_m', k_m'·|e_s|/scale')
// (e_m = −S·e_s).

struct Command {
  const char* name;
  std::function<void(Rig&)> issue;
};

constexpr saw::teleop::Gains new_gains{600, 150};
constexpr saw::teleop::ForceLimits new_limits{2, 5};
constexpr double new_scale = 2.0;

std::vector<Command> commands() {
  auto state = [](saw::StateCommand s) {
    return [s](Rig& r) { ASSERT_EQ(r.op.state_command(s), Status::ok); };
  };
  return {
      {"enable", state(saw::StateCommand::enable)},
      {"disable", state(saw::StateCommand::disable)},
      {"pause", state(saw::StateCommand::pause)},
      {"resume", state(saw::StateCommand::resume)},
      {"home", state(saw::StateCommand::home)},
      {"set_scale", [](Rig& r) { ASSERT_EQ(r.op.set_scale(new_scale), Status::ok); }},
      {"set_gains", [](Rig& r) { ASSERT_EQ(r.op.set_gains(new_gains), Status::ok); }},
      {"set_force_limits", [](Rig& r) { ASSERT_EQ(r.op.set_force_limits(new_limits), Status::ok); }},
      {"set_prediction",
       [](Rig& r) {
         ASSERT_EQ(r.op.set_prediction({true, 0.02, 0.01}), Status::ok);
       }},
      {"set_slave_offset",
       [](Rig& r) {
         ASSERT_EQ(r.op.set_slave_offset({0.01, 0, 0}), Status::ok);
       }},
      {"clutch_press", [](Rig& r) { r.master.press_clutch(true); }},
      {"clutch_release", [](Rig& r) { r.master.press_clutch(false); }},
  };
}

struct Start {
  const char* name;
  std::function<void(Rig&)> reach;
};

std::vector<Start> starts() {
  auto moved = [](Rig& r) {  // engaged at rest, then an error of ~4.5 mm (1.3 N), moving
    r.step(3);
    r.master.position = {0.054, 0.022, 0};
    r.master.velocity = {0.05, 0, 0};
    r.slave.velocity = {0, 0.02, 0};
  };
  auto command = [](saw::StateCommand s) {
    return [s](Rig& r) { ASSERT_EQ(r.op.state_command(s), Status::ok); };
  };
  return {
      {"enabled", [=](Rig& r) { moved(r), r.step(2); }},
      {"paused", [=](Rig& r) { moved(r), command(saw::StateCommand::pause)(r), r.step(2); }},
      {"disabled", [=](Rig& r) { moved(r), command(saw::StateCommand::disable)(r), r.step(2); }},
      {"clutched", [=](Rig& r) { moved(r), r.master.press_clutch(true), r.step(2); }},
      {"fault", [=](Rig& r) { moved(r), r.step(2), r.step(8, false), r.step(2); }},
  };
}

TEST(TeleopTrust, NoQueuedCommandPairMakesAForceStep) {
  int checked = 0, failed = 0;
  for (const auto& start : starts())
    for (const auto& a : commands())
      for (const auto& b : commands()) {
        const std::string what = std::string(start.name) + ": " + a.name + " + " + b.name;
        TeleopConfig c = basic();
        c.gains = {300, 300};
        c.limits = {3, 3};
        c.stale_timeout = 0.005;
        Rig rig(c);
        rig.master.position = {0.05, 0.02, 0};
        start.reach(rig);
        const auto engaged = [&rig] {
          bool clutched = false;
          EXPECT_EQ(rig.teleop.state_table().read_latest(rig.teleop.columns().clutched, clutched),
                    Status::ok);
          return rig.teleop.operating_state() == OperatingStateValue::enabled && !clutched;
        };
        const auto slave_error = [&rig] {
          saw::Vec3 e{};
          EXPECT_EQ(rig.teleop.state_table().read_latest(rig.teleop.columns().slave_error, e), Status::ok);
          return e;
        };
        const bool engaged_before = engaged();
        // Idle, the offset cancels the error every cycle: engaging starts from zero.
        const saw::Vec3 e0v = engaged_before ? slave_error() : saw::Vec3{};
        const double e0 = norm(e0v);
        if (std::string(start.name) == "enabled") {
          ASSERT_GT(e0, 0.004) << what;
        }
        a.issue(rig);
        b.issue(rig);
        rig.step(1);
        const std::string pair = std::string(a.name) + b.name;
        const auto has = [&](const char* n) { return pair.find(n) != std::string::npos; };
        const auto k = has("set_gains") ? new_gains : c.gains;
        const auto lim = has("set_force_limits") ? new_limits : c.limits;
        const double scale = has("set_scale") ? new_scale : 1.0;
        const bool disengaged = has("pause") || has("disable") || has("clutch_press");
        const double tol = 1e-6;  // a jerk-limited offset moves ~1e-9 m in its first cycle
        const double fs = norm(rig.slave.force), fm = norm(rig.master.force);
        bool ok = finite(rig.slave.force) && finite(rig.master.force) &&
                  fs <= std::min(lim.slave, k.slave * e0) + k.slave * tol &&
                  fm <= std::min(lim.master, k.master * e0 / scale) + k.master * tol;
        const saw::Vec3 e1 = engaged() ? slave_error() : saw::Vec3{};
        if (!engaged())
          ok = ok && fs == 0 && fm == 0;
        else if (engaged_before)
          ok = ok && (saw::testing::dist(e1, e0v) <= tol || (disengaged && norm(e1) <= tol));
        else
          ok = ok && norm(e1) <= tol;
        ++checked;
        if (!ok) {
          ++failed;
          ADD_FAILURE() << what << ": e_s " << e0v[0] << "," << e0v[1] << " -> " << e1[0] << "," << e1[1]
                        << ", |f_s| " << fs << " (k_s " << k.slave << ", lim " << lim.slave << "), |f_m| "
                        << fm;
        }
      }
  EXPECT_EQ(checked, 5 * 12 * 12);
  EXPECT_EQ(failed, 0);
}

// ---- A device in FAULT ----------------------------------------------------------------------

// A slave whose drive faulted (an emergency, a lost node) still publishes fresh positions; the
// teleoperation must not keep pushing the operator against it: FAULT, zero force, and why.
TEST(TeleopTrust, ASideThatReportsFaultFaultsTheTeleoperation) {
  for (const bool slave_faults : {true, false}) {
    SCOPED_TRACE(slave_faults ? "slave" : "master");
    Rig rig(basic());
    rig.step(3);
    rig.master.position[0] += 0.01;
    rig.step(1);
    ASSERT_GT(norm(rig.slave.force), 0.0);
    (slave_faults ? rig.slave : rig.master).operating = OperatingStateValue::fault;
    rig.step(1);
    EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::fault);
    EXPECT_EQ(rig.teleop.fault().code, FaultCode::device_fault);
    EXPECT_EQ(rig.teleop.fault().source_name(), slave_faults ? "slave" : "master");
    EXPECT_EQ(norm(rig.slave.force), 0.0);
    EXPECT_EQ(norm(rig.master.force), 0.0);
  }
}

// ---- A dead source behind a delay ------------------------------------------------------------

TEST(TeleopTrust, ADeadSourceBehindADelayStillFaults) {
  TeleopConfig c = basic();
  c.stale_timeout = 0.005;
  saw::testing::DelayedTeleopRig rig(c, 0.020);
  rig.step(100);
  ASSERT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
  // The master dies. Its last row reaches the teleop 20 ms later, as every row does; only when
  // that row is older than delay + stale_timeout is it stale.
  rig.step(24, /*publish_master=*/false);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled) << "within delay + stale_timeout";
  rig.step(4, /*publish_master=*/false);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, FaultCode::input_stale);
  EXPECT_EQ(rig.teleop.fault().source_name(), "master");
  EXPECT_GT(rig.teleop.fault().age_ns, 5'000'000);
  EXPECT_LE(rig.teleop.fault().age_ns, 8'000'000);
  EXPECT_EQ(norm(rig.slave.force), 0.0);
}

TEST(TeleopTrust, DelayedRowsCarryTheSourceRowsTime) {
  saw::testing::FakeDevice master("master");
  saw::teleop::DelayTask delay("master_delay", saw::TaskConfig::periodic(1ms, 0), 0.010);
  class Reader : public saw::Component {
   public:
    Reader() : Component("reader") {
      auto& r = require("arm");
      r.add_function("source_time", source_time);
      r.add_function("delay", delay);
    }
    saw::FunctionRead<saw::TimeNs> source_time, delay;
  } reader;
  saw::Manager m;
  m.add(master);
  m.add(delay);
  m.add(reader);
  m.connect("master_delay", "source", "master", "arm");
  m.connect("reader", "arm", "master_delay", "arm");
  m.start_stepped();
  saw::testing::Stepper step{m};
  for (int i = 0; i < 50; ++i) step({&master});
  saw::TimeNs t = 0, d = 0;
  ASSERT_EQ(reader.source_time(t), Status::ok);
  ASSERT_EQ(reader.delay(d), Status::ok);
  EXPECT_EQ(d, 10'000'000);
  EXPECT_EQ(t, 49'000'000 - 10'000'000) << "the row shown is the one the source wrote 10 ms ago";
  for (int i = 0; i < 30; ++i) step({});
  ASSERT_EQ(reader.source_time(t), Status::ok);
  EXPECT_EQ(t, 49'000'000) << "the source's last row, however long the delay republishes it";
}

// ---- A FAULT says why --------------------------------------------------------------------------

TEST(TeleopTrust, AFaultSaysWhyInTheStateTableTheEventAndTheLogOnce) {
  saw::LogRecord r;
  while (saw::log_ring().pop(r)) {
  }
  TeleopConfig c = basic();
  c.stale_timeout = 0.005;
  Rig rig(c);
  rig.step(10);
  rig.step(7, false);  // the master's last row is at 9 ms; at 16 ms it is 7 ms old
  ASSERT_EQ(rig.teleop.operating_state(), OperatingStateValue::fault);
  FaultInfo f;
  ASSERT_EQ(rig.op.fault(f), Status::ok);
  EXPECT_EQ(f.code, FaultCode::input_stale);
  EXPECT_EQ(f.source_name(), "master");
  EXPECT_EQ(f.age_ns, 6'000'000);
  EXPECT_EQ(f.time, 15'000'000);
  EXPECT_EQ(saw::teleop::to_string(f), "master input stale: 6.0 ms old, at t=0.015 s");
  ASSERT_EQ(rig.op.fault_events.size(), 1u);
  EXPECT_EQ(rig.op.fault_events[0].code, FaultCode::input_stale);
  rig.step(20, false);  // still faulted: no new record, no new event
  int records = 0;
  std::string text;
  while (saw::log_ring().pop(r)) {
    const std::string line = saw::format_log_record(r);
    if (line.find("FAULT") != std::string::npos) ++records, text = line;
  }
  EXPECT_EQ(records, 1);
  EXPECT_NE(text.find("master input stale: 6000000 ns old"), std::string::npos) << text;
  EXPECT_EQ(rig.op.fault_events.size(), 1u);
  // Enabling clears it, and says so.
  ASSERT_EQ(rig.op.state_command(saw::StateCommand::enable), Status::ok);
  rig.step(2);
  EXPECT_EQ(rig.teleop.fault().code, FaultCode::none);
  ASSERT_EQ(rig.op.fault_events.size(), 2u);
  EXPECT_EQ(rig.op.fault_events[1].code, FaultCode::none);
}

}  // namespace

namespace {

// A late loop: the wake-up that finds the task's deadline policy breached faults the
// teleoperation in that very cycle, zero force both ways, the figures in its reason.
TEST(TeleopTrust, ALateLoopIsAFaultWithZeroForceNamingTheFigures) {
  Rig rig(basic());
  rig.step(3);
  rig.master.position[0] += 0.01;
  rig.step(1);
  ASSERT_GT(norm(rig.slave.force), 0.5);
  saw::DeadlineBreach late;
  late.kind = saw::DeadlineBreach::Kind::share;
  late.missed = 640;
  late.periods = 1000;
  late.latency = 2'260'000;
  late.period = 1'000'000;
  saw::detail::Access::deadline_breach(rig.teleop, late);
  rig.step(1);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, FaultCode::deadline_missed);
  EXPECT_EQ(rig.teleop.fault().detail, 640u);
  EXPECT_EQ(rig.teleop.fault_reason(), "640 of 1000 periods missed");
  EXPECT_NE(saw::to_string(rig.teleop.fault()).find("640 periods in a window (last wake-up 2.3 ms late)"),
            std::string::npos)
      << saw::to_string(rig.teleop.fault());
  EXPECT_EQ(norm(rig.slave.force), 0.0);
  EXPECT_EQ(norm(rig.master.force), 0.0);
}

}  // namespace
