// A real periodic thread with one injected slow cycle: the overrun is counted, whole periods
// are skipped, and the wake-ups stay on the task's grid.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>

#include "saw/manager.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using namespace std::chrono_literals;
constexpr saw::TimeNs period = 2'000'000;

class SlowOnce : public saw::Task {
 public:
  SlowOnce() : Task("slow_once", saw::TaskConfig::periodic(std::chrono::nanoseconds(period), 0)) {}
  void run() override {
    const auto n = cycles_.fetch_add(1, std::memory_order_relaxed) + 1;
    // The previous cycle's scheduled wake-up, from this task's own statistics row.
    saw::TaskStatistics s;
    if (n <= static_cast<int>(wakeups_.size()) &&
        state_table().read_latest(statistics_column(), s) == saw::Status::ok)
      wakeups_[static_cast<std::size_t>(n - 1)] = s.last_wakeup;
    if (n == 20) {  // busy for 3.5 periods: at least 3 wake-ups must be skipped
      const auto until = saw::monotonic_now() + 7 * period / 2;
      while (saw::monotonic_now() < until) {
      }
    }
  }
  std::atomic<int> cycles_{0};
  std::array<saw::TimeNs, 50> wakeups_{};
};

TEST(Overrun, InjectedSlowCycleSkipsWholePeriodsAndKeepsPhase) {
  SlowOnce task;
  saw::Manager m;
  m.add(task);
  m.start();
  // Bounded, not asserted: the assertions below decide.
  (void)saw::testing::wait_for([&] { return task.cycles_.load() >= 60; }, 20s, 2ms);
  m.stop();
  ASSERT_GE(task.cycles_.load(), 60);
  const auto s = task.statistics();
  EXPECT_GE(s.overruns, 1u);
  EXPECT_GE(s.missed_periods, 3u);
  EXPECT_GE(s.max_compute, 7 * period / 2);
  EXPECT_EQ(task.wakeup_histogram().total(), static_cast<std::uint64_t>(task.cycles_.load()));
  // Phase: every scheduled wake-up is start + k·period, whatever was skipped.
  const auto& w = task.wakeups_;
  saw::TimeNs largest_gap = 0;
  for (std::size_t i = 3; i < w.size(); ++i) {  // rows lag a cycle: w[2] is cycle 1's
    ASSERT_GT(w[i], w[i - 1]);
    EXPECT_EQ((w[i] - w[2]) % period, 0) << "wake-up " << i << " is off the grid";
    largest_gap = std::max(largest_gap, w[i] - w[i - 1]);
  }
  EXPECT_GE(largest_gap, 4 * period) << "the slow cycle should have skipped at least 3 wake-ups";
}

}  // namespace
