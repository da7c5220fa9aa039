// Marks the threads that are inside an RT path, so tests can prove those paths do not allocate.
#pragma once

namespace saw {

namespace detail {
inline constinit thread_local bool in_rt_context = false;
}

// True while this thread runs periodic-task cycles (after start, before stop).
inline bool in_rt_context() noexcept { return detail::in_rt_context; }

// RAII: marks the current thread as running an RT path.
class RtContextScope {
 public:
  RtContextScope() noexcept : previous_(detail::in_rt_context) { detail::in_rt_context = true; }
  ~RtContextScope() { detail::in_rt_context = previous_; }
  RtContextScope(const RtContextScope&) = delete;
  RtContextScope& operator=(const RtContextScope&) = delete;

 private:
  bool previous_;
};

}  // namespace saw
