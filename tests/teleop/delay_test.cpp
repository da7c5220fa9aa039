// The simulated network link: delay, jitter and loss in each direction, repeatable, and what the
// delay task makes of it (the newest sample shown and held; commands held for a bounded time).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>

#include "saw/component.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/teleop/delay_channel.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/stepper.hpp"

namespace {

using saw::TimeNs;
using saw::teleop::DelayChannel;
using saw::teleop::LinkConfig;
constexpr TimeNs ms = 1'000'000;

// Sends sample k at k ms for n ms and returns, per receiving cycle, the sample shown (-1: none yet).
std::vector<int> run_link(LinkConfig link, int n, DelayChannel<int>* out = nullptr) {
  DelayChannel<int> c(link, ms);
  std::vector<int> shown;
  int value = -1;
  for (int k = 0; k < n; ++k) {
    c.send(k * ms, k);
    int v = 0;
    if (c.receive(k * ms, v)) value = v;
    shown.push_back(value);
  }
  if (out) *out = c;
  return shown;
}

TEST(DelayChannel, AFixedDelayShowsEachSampleExactlyThatLate) {
  const auto shown = run_link({20 * ms, 0, 0, 1}, 200);
  for (int k = 0; k < 200; ++k) EXPECT_EQ(shown[static_cast<std::size_t>(k)], k < 20 ? -1 : k - 20) << k;
}

TEST(DelayChannel, JitterNeverShowsAnOlderSampleAfterANewerOne) {
  DelayChannel<int> c({20 * ms, 10 * ms, 0, 7}, ms);
  const auto shown = run_link({20 * ms, 10 * ms, 0, 7}, 5000, &c);
  int late_seen = 0;
  for (std::size_t k = 1; k < shown.size(); ++k) {
    EXPECT_GE(shown[k], shown[k - 1]) << "the newest arrived is kept: never back in time";
    if (shown[k] >= 0) {
      const int lag = static_cast<int>(k) - shown[k];
      EXPECT_GE(lag, 20);
      EXPECT_LE(lag, 31) << "delay + jitter at most, one cycle of rounding";
      late_seen = std::max(late_seen, lag);
    }
  }
  EXPECT_GT(late_seen, 25) << "the jitter is there";
  EXPECT_GT(c.late(), 0u) << "uniform jitter of 10 periods reorders samples: some arrive after newer ones";
}

TEST(DelayChannel, LossDropsThatShareAndNeverShowsADroppedSample) {
  DelayChannel<int> c({5 * ms, 0, 0.1, 3}, ms);
  const int n = 100'000;
  std::set<int> delivered;
  int v = 0;
  for (int k = 0; k < n; ++k) {
    c.send(k * ms, k);
    if (c.receive(k * ms, v)) delivered.insert(v);
  }
  EXPECT_EQ(c.sent(), static_cast<std::uint64_t>(n));
  EXPECT_NEAR(static_cast<double>(c.lost()) / n, 0.1, 0.005);
  EXPECT_EQ(delivered.size() + c.lost(), static_cast<std::size_t>(n) - 5) << "every sample delivered or lost";
}

TEST(DelayChannel, TheSameSeedIsTheSameRunAnotherSeedIsNot) {
  const LinkConfig a{10 * ms, 8 * ms, 0.1, 42};
  LinkConfig b = a;
  b.seed = 43;
  EXPECT_EQ(run_link(a, 3000), run_link(a, 3000));
  EXPECT_NE(run_link(a, 3000), run_link(b, 3000));
}

TEST(DelayChannel, ASenderFasterThanItsPeriodOverwritesTheOldestAndCountsIt) {
  DelayChannel<int> c({10 * ms, 0, 0, 1}, ms);  // room for ~18 in flight
  for (int k = 0; k < 100; ++k) c.send(0, k);   // 100 in one instant
  EXPECT_GT(c.overwritten(), 0u);
  int v = -1;
  ASSERT_TRUE(c.receive(10 * ms, v));
  EXPECT_EQ(v, 99) << "the newest survives";
  EXPECT_THROW(DelayChannel<int>(LinkConfig{0, 0, 1.0, 1}, ms), std::invalid_argument);
  EXPECT_THROW(DelayChannel<int>(LinkConfig{-1, 0, 0, 1}, ms), std::invalid_argument);
}

// Each receive looks at the samples that may have arrived — the jitter window from the oldest not
// yet delivered — not at every sample in flight: its cost does not grow with the delay. (A figure,
// not a timing: the slots looked at are counted; the time per call is printed, never asserted.)
TEST(DelayChannel, AReceiveLooksAtTheJitterWindowNotAtEverySampleInFlight) {
  for (const TimeNs delay : {10 * ms, 100 * ms, 1000 * ms}) {
    for (const TimeNs jitter : {TimeNs{0}, 3 * ms}) {
      DelayChannel<int> c({delay, jitter, 0.1, 5}, ms);
      constexpr int n = 5000;
      std::uint64_t most = 0, delivered = 0;
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < n; ++k) {
        c.send(k * ms, k);
        const std::uint64_t before = c.scanned();
        int v = 0;
        delivered += c.receive(k * ms, v) ? 1 : 0;
        most = std::max(most, c.scanned() - before);
      }
      const double ns =
          std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / n;
      // Sent at most jitter + one period before the previous call's oldest undelivered sample
      // became due, and due by now: jitter/period + 2 slots.
      EXPECT_LE(most, static_cast<std::uint64_t>(jitter / ms) + 2)
          << "delay " << delay / ms << " ms, jitter " << jitter / ms << " ms: " << delay / ms
          << " samples in flight, not the jitter window, looked at";
      EXPECT_GT(delivered, static_cast<std::uint64_t>(n - delay / ms) / 2) << "samples still arrive";
      std::printf(
          "figure: DelayChannel::receive, delay %lld ms, jitter %lld ms, 10 %% loss: at most %llu slots, "
          "%.2f on average, %.0f ns per send+receive\n",
          static_cast<long long>(delay / ms), static_cast<long long>(jitter / ms),
          static_cast<unsigned long long>(most), static_cast<double>(c.scanned()) / n, ns);
    }
  }
}

// A controller: writes servo_cf (force x = its cycle count) through the delay task, reads measured_cp.
class Controller : public saw::Component {
 public:
  Controller() : Component("controller") {
    auto& r = require("arm");
    saw::crtk::require(r, saw::crtk::arm::servo_cf, servo_cf);
    saw::crtk::require(r, saw::crtk::arm::measured_cp, measured_cp);
  }
  saw::FunctionWrite<saw::Wrench> servo_cf;
  saw::FunctionRead<saw::Pose> measured_cp;
};

struct LinkRig {
  explicit LinkRig(saw::teleop::DelayConfig c)
      : delay("link", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0), c) {
    manager.add(device);
    manager.add(delay);
    manager.add(controller);
    manager.connect("link", "source", "device", "arm");
    manager.connect("controller", "arm", "link", "arm");
    manager.start_stepped();
  }
  // One period: the device publishes its position x = k, the controller (if sending) commands k.
  void step(bool send) {
    device.position = {static_cast<double>(k), 0, 0};
    if (send) {
      EXPECT_EQ(controller.servo_cf(saw::Wrench{{static_cast<double>(k), 0, 0}, {}}), saw::Status::ok);
    }
    stepper({&device});
    ++k;
  }
  int k = 0;
  saw::testing::FakeDevice device{"device"};
  saw::teleop::DelayTask delay;
  Controller controller;
  saw::Manager manager;
  saw::testing::Stepper stepper{manager};
};

TEST(DelayTask, CommandsTravelTheirOwnLinkAndAreHeldThroughLosses) {
  saw::teleop::DelayConfig c;
  c.measured.delay = 0;
  c.commands = {20 * ms, 0, 0.3, 5};  // a bad link: 30 % of the commands lost
  LinkRig rig(c);
  int first = -1;
  for (int i = 0; i < 300; ++i) {
    const int before = rig.device.commands;
    const double last = rig.device.force[0];
    rig.step(true);
    if (rig.device.commands > 0 && first < 0) first = rig.k;
    if (first >= 0 && rig.k > first) {
      EXPECT_EQ(rig.device.commands, before + 1) << "a command every cycle, lost ones held, at " << rig.k;
      EXPECT_GE(rig.device.force[0], last) << "never an older command after a newer one";
      EXPECT_GE(rig.k - rig.device.force[0], 20) << "the link's delay";
    }
  }
  EXPECT_GE(first, 20) << "nothing reaches the device before the delay";
  EXPECT_GT(rig.delay.commands_link().lost(), 50u);
  // The controller dies: the device end holds the last command a bounded time, then stops, so the
  // device's own watchdog notices.
  const int at_death = rig.device.commands;
  for (int i = 0; i < 100; ++i) rig.step(false);
  const int held = rig.device.commands - at_death;
  EXPECT_GE(held, 20) << "commands still in flight arrive";
  EXPECT_LE(held, 20 + 5 + 2) << "then the last one is held for at most 5 periods";
}

TEST(DelayTask, MeasurementsAreShownNewestFirstAndHeldThroughJitterAndLoss) {
  saw::teleop::DelayConfig c;
  c.measured = {20 * ms, 10 * ms, 0.1, 9};
  LinkRig rig(c);
  double shown_before = -1;
  int lag_max = 0;
  for (int i = 0; i < 2000; ++i) {
    rig.step(false);
    saw::Pose p;
    ASSERT_EQ(rig.controller.measured_cp(p), saw::Status::ok);
    if (i > 40) {
      EXPECT_GE(p.position[0], shown_before) << "never back in time";
      const int lag = rig.k - 1 - static_cast<int>(p.position[0]);
      EXPECT_GE(lag, 20);
      lag_max = std::max(lag_max, lag);
    }
    shown_before = p.position[0];
  }
  EXPECT_GT(lag_max, 25) << "jitter and losses add to the delay";
  EXPECT_GT(rig.delay.measured_link().lost(), 100u);
}

}  // namespace
