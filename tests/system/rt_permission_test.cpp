// Without permission for SCHED_FIFO a periodic task still runs, and the manager says so once.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "saw/manager.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using namespace std::chrono_literals;

class Counter : public saw::Task {
 public:
  Counter() : Task("counter", saw::TaskConfig::periodic(1ms, 80)) {}
  void run() override { cycles_.fetch_add(1, std::memory_order_relaxed); }
  std::atomic<int> cycles_{0};
};

// Runs in the death-test child: drops the right to real-time scheduling, then runs a task.
[[noreturn]] void run_unprivileged() {
  const rlimit none{0, 0};
  setrlimit(RLIMIT_RTPRIO, &none);
  if (geteuid() == 0 && setuid(65534) != 0) std::_Exit(3);  // root ignores RLIMIT_RTPRIO
  Counter c;
  saw::Manager m;
  m.add(c);
  m.start();
  // Bounded, not asserted: the parent checks the cycles-ok line.
  (void)saw::testing::wait_for([&] { return c.cycles_.load() >= 50; }, 10s, 2ms);
  m.stop();
  std::fprintf(stderr, "cycles-ok=%d\n", c.cycles_.load() >= 50 ? 1 : 0);
  std::_Exit(m.rt_warnings().empty() ? 4 : 0);
}

TEST(RtPermission, RunsWithoutSchedFifoAndWarnsOnce) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  // The warning names the task and the missing priority, exactly once; the task still cycles.
  EXPECT_EXIT(run_unprivileged(), ::testing::ExitedWithCode(0),
              "^sawrt WARNING: running without full real-time guarantees:\n"
              "(  - [^\n]*\n)*"
              "  - task 'counter': SCHED_FIFO priority 80: Operation not permitted\n"
              "[^\n]*docs/deploy.md[^\n]*\n"
              "cycles-ok=1\n$");
}

}  // namespace
