// RT-safe logging: fixed-size records in a lock-free ring, formatted and printed by a non-RT thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <type_traits>

#include "saw/cache_line.hpp"
#include "saw/clock.hpp"

namespace saw {

enum class LogLevel : std::uint8_t { debug, info, warning, error };

// One argument of a log record: a number or a string literal (never a heap string).
struct LogArg {
  enum class Kind : std::uint8_t { none, i64, u64, f64, text } kind = Kind::none;
  union {
    std::int64_t i;
    std::uint64_t u;
    double f;
    const char* s;
  };
  LogArg() : i(0) {}
};

struct LogRecord {
  static constexpr int max_args = 6;
  TimeNs time = 0;
  LogLevel level = LogLevel::info;
  const char* source = "";  // a literal or a name that outlives the log (component names)
  const char* format = "";  // a literal; "{}" marks each argument, "{:x}" one in hex (0x2310)
  LogArg args[max_args];
};

// A bounded multi-producer single-consumer ring (Vyukov's per-cell sequence numbers). Pushing
// never blocks; when the ring is full the record is counted as dropped and the drain says so.
class LogRing {
 public:
  static constexpr std::size_t capacity = 1024;
  bool push(const LogRecord& r) noexcept;
  bool pop(LogRecord& r) noexcept;
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  struct Cell {
    std::atomic<std::uint64_t> seq;
    LogRecord record;
  };
  struct Cells {
    Cells();
    Cell cells[capacity];
  };
  Cells cells_;
  alignas(cache_line) std::atomic<std::uint64_t> enqueue_{0};
  alignas(cache_line) std::atomic<std::uint64_t> dequeue_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

// The process-wide ring (static storage, no allocation).
LogRing& log_ring() noexcept;

namespace detail {
template <class T>
LogArg to_log_arg(T v) noexcept {
  LogArg a;
  if constexpr (std::is_same_v<std::decay_t<T>, const char*> || std::is_same_v<std::decay_t<T>, char*>) {
    a.kind = LogArg::Kind::text;
    a.s = v;
  } else if constexpr (std::is_floating_point_v<T>) {
    a.kind = LogArg::Kind::f64;
    a.f = static_cast<double>(v);
  } else if constexpr (std::is_signed_v<T> || std::is_enum_v<T>) {
    a.kind = LogArg::Kind::i64;
    a.i = static_cast<std::int64_t>(v);
  } else {
    a.kind = LogArg::Kind::u64;
    a.u = static_cast<std::uint64_t>(v);
  }
  return a;
}
}  // namespace detail

// RT-safe: copies the literal pointers and numbers into the ring. Returns false if dropped.
template <class... Args>
bool log(LogLevel level, const char* source, const char* format, Args... args) noexcept {
  static_assert(sizeof...(Args) <= LogRecord::max_args, "too many log arguments");
  LogRecord r;
  r.time = monotonic_now();
  r.level = level;
  r.source = source;
  r.format = format;
  int i = 0;
  ((r.args[i++] = detail::to_log_arg(args)), ...);
  return log_ring().push(r);
}

// Formats a record: "{}" replaced by each argument in turn.
std::string format_log_record(const LogRecord& r);

// A non-RT thread that drains the ring into a sink (stderr by default) until destroyed.
class LogDrain {
 public:
  using Sink = std::function<void(const std::string&)>;
  explicit LogDrain(Sink sink = {});
  ~LogDrain();
  LogDrain(const LogDrain&) = delete;
  LogDrain& operator=(const LogDrain&) = delete;

 private:
  void drain_once();

  Sink sink_;
  std::atomic<bool> stop_{false};
  std::uint64_t dropped_reported_ = 0;
  std::thread thread_;
};

}  // namespace saw
