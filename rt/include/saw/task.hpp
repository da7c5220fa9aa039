// Task: a component with its own thread, periodic (RT, SCHED_FIFO) or continuous.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <thread>

#include "saw/component.hpp"
#include "saw/deadline.hpp"
#include "saw/latency_histogram.hpp"

namespace saw {

struct TaskConfig {
  std::chrono::nanoseconds period{0};  // zero: continuous (run() back to back)
  int priority = 0;                    // SCHED_FIFO 1..99; 0: SCHED_OTHER
  int cpu = -1;                        // pinned CPU, -1: any
  // Phase within the period. Periodic tasks wake on a grid aligned to CLOCK_MONOTONIC (the same
  // in every process of the host) plus this offset: a consumer placed after its producers reads
  // the rows of the same period, in this process and in others.
  std::chrono::nanoseconds offset{0};
  std::size_t stack_prefault = 256 * 1024;
  std::size_t histogram_bins = 1000;  // 1 µs each
  // When missed periods are a breach (periodic tasks; off unless set: a deployment sets
  // DeadlinePolicy::standard() unless its file says otherwise).
  DeadlinePolicy deadline{};
  // How far back its state table keeps rows (periodic tasks; 0: StateTable::default_rows). The
  // recorder and other history readers lose rows when they fall further behind than this.
  std::chrono::nanoseconds history{0};

  static TaskConfig periodic(std::chrono::nanoseconds period, int priority = 80, int cpu = -1) {
    return {period, priority, cpu};
  }
  static TaskConfig continuous() { return {}; }
  bool is_periodic() const noexcept { return period.count() > 0; }
  // Its cycles are an RT path: periodic, or continuous and asking for SCHED_FIFO.
  bool is_rt() const noexcept { return is_periodic() || priority > 0; }
};

// Period and compute-time statistics; a column ("period_statistics") of the task's state table.
struct TaskStatistics {
  static constexpr std::string_view type_name = "saw::TaskStatistics";
  static constexpr std::uint32_t layout_version = 1;
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;        // cycles that ended after their next wake-up
  std::uint64_t missed_periods = 0;  // wake-ups skipped to keep phase
  TimeNs period = 0;
  TimeNs last_wakeup_latency = 0, max_wakeup_latency = 0;
  TimeNs last_compute = 0, max_compute = 0;
  double mean_compute = 0;
  TimeNs last_wakeup = 0;  // scheduled time of the last wake-up
};
// Read by other processes byte for byte: a layout change must bump layout_version (and this).
static_assert(sizeof(TaskStatistics) == 80 && offsetof(TaskStatistics, period) == 24 &&
              offsetof(TaskStatistics, mean_compute) == 64 && offsetof(TaskStatistics, last_wakeup) == 72);

class Task : public Component {
 public:
  Task(std::string name, TaskConfig config, std::size_t state_rows = StateTable::default_rows);
  ~Task() override;

  bool has_thread() const noexcept override { return true; }
  const TaskConfig& config() const noexcept { return config_; }
  const LatencyHistogram& wakeup_histogram() const noexcept { return histogram_; }
  // The newest statistics row (readable from any thread).
  TaskStatistics statistics() const noexcept;
  StateColumn<TaskStatistics> statistics_column() const noexcept { return stats_column_; }
  // Once Manager::start() has returned: what the thread could not get (SCHED_FIFO, affinity),
  // empty if all. The manager's rt_warnings() lists it too.
  const std::string& rt_setup_error() const noexcept { return rt_setup_error_; }
  // Wake-ups that found the deadline policy breached (see on_deadline_breach()).
  std::uint64_t deadline_breaches() const noexcept {
    return deadline_breaches_.load(std::memory_order_relaxed);
  }

 protected:
  // RT, in the task's thread, right before a cycle whose wake-up found the deadline policy
  // breached (every such wake-up, until a cycle is on time again or the window recovers). The
  // task has said it once in the log; a component that drives something faults here and takes
  // its safe state in the cycle that follows. The default does nothing more.
  virtual void on_deadline_breach(const DeadlineBreach&) noexcept {}

 private:
  // The manager's, through detail::Access.
  friend struct detail::Access;
  // The thread sets itself up, reports thread_ready(), then waits until `first_wakeup` is
  // non-zero and runs until `running` is false.
  void start_thread(const std::atomic<TimeNs>& first_wakeup, const std::atomic<bool>& running);
  bool thread_ready() const noexcept { return ready_.load(std::memory_order_acquire); }
  void join();
  // Stepped mode: one cycle at simulated time t.
  void step(TimeNs t) noexcept;

  void thread_main(const std::atomic<TimeNs>& first_wakeup, const std::atomic<bool>& running);
  void periodic_loop(TimeNs first_wakeup, const std::atomic<bool>& running) noexcept;
  void continuous_loop(const std::atomic<bool>& running) noexcept;
  void watch_deadline(TimeNs latency) noexcept;
  // A breach: counted, said once per episode, handed to on_deadline_breach().
  void breach(const DeadlineBreach& b) noexcept;
  void account(TimeNs scheduled, TimeNs woke, TimeNs end, std::uint64_t overruns,
               std::uint64_t missed) noexcept;

  TaskConfig config_;
  LatencyHistogram histogram_;
  TaskStatistics stats_{};
  StateColumn<TaskStatistics> stats_column_;
  std::thread thread_;
  std::atomic<bool> ready_{false};
  std::string rt_setup_error_;  // written by the thread before ready_ (release)
  DeadlineMonitor deadline_;
  bool breached_ = false;  // the last wake-up breached the policy (for one log line per episode)
  std::atomic<std::uint64_t> deadline_breaches_{0};
};

// "12 periods missed in a row (last wake-up 11.8 ms late)", "312 of 1000 periods missed": for
// people, not RT code (it allocates).
std::string to_string(const DeadlineBreach& b);

}  // namespace saw
