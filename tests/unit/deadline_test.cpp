// Deadline supervision: the monitor's arithmetic, and a periodic task on a real thread whose own
// cycles overrun (lateness made by the test, so a slow machine can only add to it).
#include "saw/deadline.hpp"

#include <gtest/gtest.h>

#include <atomic>

#include "core_fixtures.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using saw::DeadlineBreach;
using saw::DeadlineMonitor;
using saw::DeadlinePolicy;
constexpr saw::TimeNs ms = 1'000'000;

TEST(DeadlineMonitor, AWakeUpLateByTheLimitIsABreachNamingThePeriodsAndTheLateness) {
  DeadlineMonitor m(DeadlinePolicy{5, 0, 1000}, ms);
  DeadlineBreach b;
  EXPECT_FALSE(m.on_wakeup(4 * ms + ms / 2, b)) << "4 periods late: under the limit";
  m.on_finish(4);
  EXPECT_FALSE(m.on_wakeup(0, b));
  m.on_finish(0);
  EXPECT_TRUE(m.on_wakeup(5 * ms + 300'000, b));
  EXPECT_EQ(b.kind, DeadlineBreach::Kind::in_a_row);
  EXPECT_EQ(b.missed, 5u);
  EXPECT_EQ(b.latency, 5 * ms + 300'000);
  EXPECT_EQ(saw::to_string(b), "5 periods missed in a row (last wake-up 5.3 ms late)");
}

TEST(DeadlineMonitor, PeriodsInARowAreThoseWithNoCycleStartBetweenTwoCycles) {
  DeadlineMonitor m(DeadlinePolicy{5, 0, 1000}, ms);
  DeadlineBreach b;
  EXPECT_FALSE(m.on_wakeup(ms, b));  // one period late
  m.on_finish(4);                    // ... and ran on into three more: the pacer skipped 4
  EXPECT_EQ(m.in_a_row(), 1u);
  EXPECT_TRUE(m.on_wakeup(2 * ms, b)) << "3 periods overrun into, and 2 late: 5 with no cycle start";
  EXPECT_EQ(b.missed, 5u);
  m.on_finish(2);  // the 2 it was late by, nothing more
  EXPECT_FALSE(m.on_wakeup(ms, b)) << "the stall is over: a cycle started in between";
  EXPECT_EQ(m.in_a_row(), 1u);
  m.on_finish(1);
  // A loop that runs one period in three never misses 5 in a row, however long it goes on.
  for (int i = 0; i < 100; ++i) {
    EXPECT_FALSE(m.on_wakeup(i % 2 == 0 ? 0 : ms, b));
    m.on_finish(2);
  }
}

TEST(DeadlineMonitor, AStarvedLoopBreachesTheShareOncePerWindow) {
  DeadlineMonitor m(DeadlinePolicy{0, 0.1, 100}, ms);
  DeadlineBreach b;
  int breaches = 0;
  // A loop that runs one period in three (the emulated guest): never 5 in a row, 2/3 missed.
  for (int i = 0; i < 34; ++i) {  // 34 cycles: 102 periods, the window's first 100 and 2 more
    breaches += m.on_wakeup(0, b);
    m.on_finish(2);
  }
  breaches += m.on_wakeup(0, b);
  EXPECT_EQ(breaches, 1);
  EXPECT_EQ(b.kind, DeadlineBreach::Kind::share);
  EXPECT_EQ(b.periods, 102u);
  EXPECT_EQ(b.missed, 68u);
  EXPECT_EQ(saw::to_string(b), "68 of 102 periods missed (last wake-up 0.0 ms late)");
}

TEST(DeadlineMonitor, AtTheShareOrOffNothingBreaches) {
  DeadlineMonitor at(DeadlinePolicy{0, 0.1, 100}, ms), off(DeadlinePolicy{}, ms);
  DeadlineBreach b;
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t skip = i % 10 == 0 ? 1 : 0;  // 1 in 11 periods: under a tenth
    EXPECT_FALSE(at.on_wakeup(0, b));
    at.on_finish(skip);
    EXPECT_FALSE(off.on_wakeup(100 * ms, b));
    off.on_finish(100);
  }
}

// A task whose third cycle computes for 30 periods: the wake-up after it breaches the policy.
class Stalling : public saw::Task {
 public:
  explicit Stalling(DeadlinePolicy p, saw::TimeNs stall_every = 0, saw::TimeNs stall = 30 * ms)
      : Task("stalling", config(p)), every_(stall_every), stall_(stall) {}
  static saw::TaskConfig config(DeadlinePolicy p) {
    auto c = saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0);
    c.deadline = p;
    return c;
  }
  void run() override {
    ++cycles_;
    if (every_ == 0 ? cycles_ == 3 : true) {
      const saw::TimeNs until = saw::monotonic_now() + stall_;
      while (saw::monotonic_now() < until) {
      }
    }
  }
  std::atomic<int> breaches{0};
  DeadlineBreach first{};

 protected:
  void on_deadline_breach(const DeadlineBreach& b) noexcept override {
    if (breaches.load(std::memory_order_relaxed) == 0) first = b;
    breaches.fetch_add(1, std::memory_order_release);
  }

 private:
  saw::TimeNs every_, stall_;
  int cycles_ = 0;
};

TEST(TaskDeadline, AStalledCycleOnARealThreadIsABreachAtTheNextWakeUp) {
  Stalling t(DeadlinePolicy{5, 0, 1000});
  saw::Manager m;
  m.add(t);
  m.start();
  ASSERT_TRUE(saw::testing::wait_for([&] { return t.breaches.load(std::memory_order_acquire) > 0; }));
  m.stop();
  EXPECT_EQ(t.first.kind, DeadlineBreach::Kind::in_a_row);
  EXPECT_GE(t.first.missed, 29u) << "the stall skipped at least 29 periods";
  EXPECT_GE(t.deadline_breaches(), 1u);
}

TEST(TaskDeadline, ALoopThatMissesHalfItsPeriodsBreachesTheShare) {
  // Every cycle computes for 1.5 periods: it runs every other period, never 5 missed in a row.
  Stalling t(DeadlinePolicy{0, 0.1, 100}, 1, 3 * ms / 2);
  saw::Manager m;
  m.add(t);
  m.start();
  ASSERT_TRUE(saw::testing::wait_for([&] { return t.breaches.load(std::memory_order_acquire) > 0; }));
  m.stop();
  EXPECT_EQ(t.first.kind, DeadlineBreach::Kind::share);
  EXPECT_GE(t.first.missed * 2, t.first.periods) << saw::to_string(t.first);
}

TEST(TaskDeadline, WithThePolicyOffAStallIsCountedNeverABreach) {
  Stalling t(DeadlinePolicy{});
  saw::Manager m;
  m.add(t);
  m.start();
  ASSERT_TRUE(saw::testing::wait_for([&] { return t.statistics().cycles > 10; }));
  m.stop();
  EXPECT_GE(t.statistics().missed_periods, 29u);
  EXPECT_EQ(t.breaches.load(), 0);
  EXPECT_EQ(t.deadline_breaches(), 0u);
}

}  // namespace
