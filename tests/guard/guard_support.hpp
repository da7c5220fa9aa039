// Helpers of the guard tests: a task that runs a given body, running managers on real threads,
// and the one expectation every clean RT path must meet.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <functional>

#include "rt_guard.hpp"
#include "saw/manager.hpp"
#include "saw/testing/wait_for.hpp"

namespace saw::testing {

// The violations a test can require to be zero: page faults only when memory is locked.
inline std::uint64_t findings(const GuardCounts& c) {
  return c.violations() - (memory_locked() ? 0 : c.minor_faults);
}

// On a CI machine (CI set, as .ci/run runs) a guard that checks less than a test says is a
// failure: CI must not stay green over a check it did not make.
inline bool in_ci() noexcept {
  const char* ci = std::getenv("CI");
  return ci != nullptr && *ci != '\0';
}

// The guard cannot make one of its checks here (`what`, streamed: what and why): in CI a
// failure naming it, elsewhere a skip that says it (ends the test; what it checked stands).
#define SAW_GUARD_CANNOT_CHECK(what)                                                     \
  do {                                                                                   \
    if (::saw::testing::in_ci()) {                                                       \
      ADD_FAILURE() << what << " (CI is set: the RT guard must make every check there)"; \
    } else {                                                                             \
      GTEST_SKIP() << what;                                                              \
    }                                                                                    \
  } while (0)

// Every violation zero; page faults with them only when memory is locked, and when it is not
// the test says so (above) rather than passing on fewer checks.
#define EXPECT_RT_CLEAN(counts)                                                             \
  do {                                                                                      \
    EXPECT_EQ(::saw::testing::findings(counts), 0u) << ::saw::testing::describe(counts);    \
    if (!::saw::testing::memory_locked())                                                   \
      SAW_GUARD_CANNOT_CHECK(                                                               \
          "page faults in RT cycles not checked: " << ::saw::testing::memory_lock_error()); \
  } while (0)

// A task whose run() is `body` (set before start; called with the cycle's index from 0).
class BodyTask : public Task {
 public:
  BodyTask(std::string name, TaskConfig config, std::function<void(std::uint64_t)> body)
      : Task(std::move(name), config), body_(std::move(body)) {}
  void run() override { body_(cycles_.fetch_add(1, std::memory_order_relaxed)); }
  std::uint64_t cycles() const noexcept { return cycles_.load(std::memory_order_relaxed); }

 private:
  std::function<void(std::uint64_t)> body_;
  std::atomic<std::uint64_t> cycles_{0};
};

// Runs the manager on real threads until `done` (polled from this thread, which is not RT) or
// 20 s, then stops it; the caller asserts on what happened.
template <class Done>
void run_threads_until(Manager& m, Done done) {
  m.start();
  (void)wait_for(done, std::chrono::seconds(20), std::chrono::milliseconds(2));
  m.stop();
}

}  // namespace saw::testing
