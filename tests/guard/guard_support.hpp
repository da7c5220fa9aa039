// Helpers of the guard tests: a task that runs a given body, running managers on real threads,
// and the one expectation every clean RT path must meet.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>

#include "rt_guard.hpp"
#include "saw/manager.hpp"
#include "saw/testing/wait_for.hpp"

namespace saw::testing {

// The violations a test can require to be zero: page faults only when memory is locked.
inline std::uint64_t findings(const GuardCounts& c) {
  return c.violations() - (memory_locked() ? 0 : c.minor_faults);
}

#define EXPECT_RT_CLEAN(counts) \
  EXPECT_EQ(::saw::testing::findings(counts), 0u) << ::saw::testing::describe(counts)

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
