#include "saw/task.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <stdexcept>

#include "saw/detail/access.hpp"
#include "saw/detail/pacer.hpp"
#include "saw/log.hpp"
#include "saw/rt_context.hpp"
#include "saw/rt_thread.hpp"

namespace saw {

namespace {

// The rows its history needs: `history` of periods, when set and no other size was asked for.
std::size_t rows_for(const TaskConfig& c, std::size_t state_rows) {
  if (state_rows != StateTable::default_rows || c.history.count() <= 0 || !c.is_periodic()) return state_rows;
  const auto rows = static_cast<std::size_t>((c.history + c.period - std::chrono::nanoseconds(1)) / c.period);
  return std::max(rows, StateTable::default_rows);
}

}  // namespace

Task::Task(std::string name, TaskConfig config, std::size_t state_rows)
    : Component(std::move(name), rows_for(config, state_rows)),
      config_(config),
      histogram_(config.histogram_bins) {
  if (config_.period.count() < 0) throw std::invalid_argument("task '" + this->name() + "': negative period");
  if (config_.priority < 0 || config_.priority > 99)
    throw std::invalid_argument("task '" + this->name() + "': priority must be 0..99");
  if (config_.deadline.share < 0 || config_.deadline.share >= 1 ||
      (config_.deadline.share > 0 && config_.deadline.window == 0))
    throw std::invalid_argument("task '" + this->name() +
                                "': a deadline share must be in [0, 1) over a window of at least one period");
  stats_.period = config_.period.count();
  deadline_ = DeadlineMonitor(config_.deadline, config_.period.count());
  stats_column_ = state_table().add_column("period_statistics", &stats_);
  provide("task").add_command_read("period_statistics", stats_column_);
}

Task::~Task() { join(); }

TaskStatistics Task::statistics() const noexcept {
  TaskStatistics s;
  if (state_table().read_latest(stats_column_, s) != Status::ok) return {};
  return s;
}

void Task::start_thread(const std::atomic<TimeNs>& first_wakeup, const std::atomic<bool>& running) {
  thread_ = std::thread([this, &first_wakeup, &running] { thread_main(first_wakeup, running); });
}

void Task::join() {
  if (thread_.joinable()) thread_.join();
}

void Task::thread_main(const std::atomic<TimeNs>& first_wakeup, const std::atomic<bool>& running) {
  std::string error;
  if (config_.priority > 0) error = rt::set_fifo(config_.priority);
  if (config_.cpu >= 0)
    if (auto e = rt::set_affinity(config_.cpu); !e.empty()) error += (error.empty() ? "" : "; ") + e;
  rt::prefault_stack(config_.stack_prefault);
  rt_setup_error_ = std::move(error);
  ready_.store(true, std::memory_order_release);
  // Wait (not an RT path yet) until every task is set up and the common first wake-up is known.
  first_wakeup.wait(0, std::memory_order_acquire);
  if (config_.is_periodic())
    periodic_loop(first_wakeup.load(std::memory_order_acquire), running);
  else
    continuous_loop(running);
}

void Task::account(TimeNs scheduled, TimeNs woke, TimeNs end, std::uint64_t overruns,
                   std::uint64_t missed) noexcept {
  const TimeNs compute = end - woke;
  ++stats_.cycles;
  stats_.overruns = overruns;
  stats_.missed_periods = missed;
  stats_.last_compute = compute;
  if (compute > stats_.max_compute) stats_.max_compute = compute;
  stats_.mean_compute +=
      (static_cast<double>(compute) - stats_.mean_compute) / static_cast<double>(stats_.cycles);
  stats_.last_wakeup = scheduled;
}

void Task::periodic_loop(TimeNs first_wakeup, const std::atomic<bool>& running) noexcept {
  RtContextScope rt_scope;
  // The first multiple of the period at or after the common start, plus this task's offset.
  const TimeNs period = config_.period.count();
  const TimeNs first = (first_wakeup + period - 1) / period * period + config_.offset.count();
  detail::Pacer pacer(first, period);
  while (running.load(std::memory_order_acquire)) {
    const TimeNs scheduled = pacer.next_wakeup();
    const timespec ts = to_timespec(scheduled);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    const RtCycleScope observed(name().c_str());  // from wake-up to the next sleep
    const TimeNs woke = monotonic_now();
    const TimeNs latency = woke - scheduled;
    histogram_.record(latency);
    stats_.last_wakeup_latency = latency;
    if (latency > stats_.max_wakeup_latency) stats_.max_wakeup_latency = latency;
    watch_deadline(latency);
    detail::Access::cycle(*this, woke);
    const TimeNs end = monotonic_now();
    deadline_.on_finish(pacer.finish_cycle(end));
    account(scheduled, woke, end, pacer.overruns(), pacer.missed_periods());
  }
}

void Task::watch_deadline(TimeNs latency) noexcept {
  DeadlineBreach b;
  const bool breached = deadline_.on_wakeup(latency, b);
  if (breached) breach(b);
  breached_ = breached;
}

void Task::breach(const DeadlineBreach& b) noexcept {
  deadline_breaches_.fetch_add(1, std::memory_order_relaxed);
  if (!breached_) {  // once per episode: every late wake-up of a stall would flood the log
    const double late_ms = std::round(static_cast<double>(b.latency) * 1e-5) / 10;
    if (b.kind == DeadlineBreach::Kind::in_a_row)
      saw::log(LogLevel::error, name().c_str(),
               "deadline: {} periods missed in a row (last wake-up {} ms late)", b.missed, late_ms);
    else
      saw::log(LogLevel::error, name().c_str(), "deadline: {} of {} periods missed (last wake-up {} ms late)",
               b.missed, b.periods, late_ms);
  }
  on_deadline_breach(b);
}

std::string to_string(const DeadlineBreach& b) {
  char s[128];
  const double late_ms = static_cast<double>(b.latency) * 1e-6;
  if (b.kind == DeadlineBreach::Kind::in_a_row)
    std::snprintf(s, sizeof s, "%llu periods missed in a row (last wake-up %.1f ms late)",
                  static_cast<unsigned long long>(b.missed), late_ms);
  else
    std::snprintf(s, sizeof s, "%llu of %llu periods missed (last wake-up %.1f ms late)",
                  static_cast<unsigned long long>(b.missed), static_cast<unsigned long long>(b.periods),
                  late_ms);
  return s;
}

void Task::continuous_loop(const std::atomic<bool>& running) noexcept {
  RtContextScope rt_scope(config_.is_rt());
  while (running.load(std::memory_order_acquire)) {
    const RtCycleScope observed(name().c_str());
    const TimeNs woke = monotonic_now();
    detail::Access::cycle(*this, woke);
    account(woke, woke, monotonic_now(), 0, 0);
  }
}

void Task::step(TimeNs t) noexcept {
  RtContextScope rt_scope(config_.is_rt());
  const RtCycleScope observed(name().c_str());
  stats_.last_wakeup_latency = 0;
  detail::Access::cycle(*this, t);
  account(t, t, t, 0, 0);
}

}  // namespace saw
