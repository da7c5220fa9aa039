// Marks the threads that are inside an RT path, so tests can prove those paths do not allocate.
#pragma once

#include <atomic>

namespace saw {

namespace detail {
inline constinit thread_local bool in_rt_context = false;
}

// True while this thread runs RT task cycles: a periodic task's thread from its first sleep
// until stop, a continuous task that asked for SCHED_FIFO likewise, and any task's stepped cycle.
inline bool in_rt_context() noexcept { return detail::in_rt_context; }

// RAII: marks the current thread as running an RT path (if `rt`; else leaves it as it is).
class RtContextScope {
 public:
  explicit RtContextScope(bool rt = true) noexcept : previous_(detail::in_rt_context) {
    detail::in_rt_context = previous_ || rt;
  }
  ~RtContextScope() { detail::in_rt_context = previous_; }
  RtContextScope(const RtContextScope&) = delete;
  RtContextScope& operator=(const RtContextScope&) = delete;

 private:
  bool previous_;
};

// Instrumentation for the guard tests (tests/guard): a task's thread calls begin() when it wakes
// for a cycle and end() before it sleeps again (stepped: around the cycle), so the guard can
// sample the thread's context switches and page faults around the cycle's work, leaving out
// the one sleep per cycle. Installed before any task starts; null (always, outside the guard)
// it costs one atomic load per cycle.
struct RtCycleObserver {
  void (*begin)(const char* task) noexcept;
  void (*end)(const char* task) noexcept;
};

namespace detail {
inline constinit std::atomic<const RtCycleObserver*> rt_cycle_observer{nullptr};
}

inline void set_rt_cycle_observer(const RtCycleObserver* o) noexcept {
  detail::rt_cycle_observer.store(o, std::memory_order_release);
}

// RAII, in the task loops: brackets one cycle's work for the observer, if any.
class RtCycleScope {
 public:
  explicit RtCycleScope(const char* task) noexcept
      : observer_(detail::rt_cycle_observer.load(std::memory_order_acquire)), task_(task) {
    if (observer_ != nullptr) observer_->begin(task_);
  }
  ~RtCycleScope() {
    if (observer_ != nullptr) observer_->end(task_);
  }
  RtCycleScope(const RtCycleScope&) = delete;
  RtCycleScope& operator=(const RtCycleScope&) = delete;

 private:
  const RtCycleObserver* observer_;
  const char* task_;
};

}  // namespace saw
