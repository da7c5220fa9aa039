// Monotonic time in nanoseconds, the one clock every task and table uses.
#pragma once

#include <cstdint>
#include <ctime>

namespace saw {

using TimeNs = std::int64_t;

inline TimeNs monotonic_now() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

inline timespec to_timespec(TimeNs t) {
  return timespec{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
}

}  // namespace saw
