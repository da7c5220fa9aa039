#include "saw/log.hpp"

#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>

namespace saw {

LogRing::Cells::Cells() {
  for (std::size_t i = 0; i < capacity; ++i) cells[i].seq.store(i, std::memory_order_relaxed);
}

bool LogRing::push(const LogRecord& r) noexcept {
  auto pos = enqueue_.load(std::memory_order_relaxed);
  for (;;) {
    Cell& cell = cells_.cells[pos % capacity];
    const auto seq = cell.seq.load(std::memory_order_acquire);
    const auto diff = static_cast<std::int64_t>(seq) - static_cast<std::int64_t>(pos);
    if (diff == 0) {
      if (enqueue_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
        cell.record = r;
        cell.seq.store(pos + 1, std::memory_order_release);
        return true;
      }
    } else if (diff < 0) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    } else {
      pos = enqueue_.load(std::memory_order_relaxed);
    }
  }
}

bool LogRing::pop(LogRecord& r) noexcept {
  const auto pos = dequeue_.load(std::memory_order_relaxed);
  Cell& cell = cells_.cells[pos % capacity];
  const auto seq = cell.seq.load(std::memory_order_acquire);
  if (static_cast<std::int64_t>(seq) - static_cast<std::int64_t>(pos + 1) < 0) return false;
  r = cell.record;
  cell.seq.store(pos + capacity, std::memory_order_release);
  dequeue_.store(pos + 1, std::memory_order_relaxed);
  return true;
}

LogRing& log_ring() noexcept {
  static LogRing ring;
  return ring;
}

std::string format_log_record(const LogRecord& r) {
  static constexpr const char* level_names[] = {"debug", "info", "warning", "error"};
  char head[96];
  std::snprintf(head, sizeof head, "[%.6f] %s %s: ", static_cast<double>(r.time) * 1e-9,
                level_names[static_cast<int>(r.level)], r.source);
  std::string out = head;
  int next = 0;
  for (const char* p = r.format; *p != '\0'; ++p) {
    // "{:x}": an unsigned number in hex, at least 4 digits (CANopen codes: 0x2310).
    if (std::strncmp(p, "{:x}", 4) == 0 && next < LogRecord::max_args) {
      const LogArg& a = r.args[next++];
      char buf[32];
      const std::uint64_t v = a.kind == LogArg::Kind::i64 ? static_cast<std::uint64_t>(a.i) : a.u;
      std::snprintf(buf, sizeof buf, "0x%04" PRIX64, v);
      out += buf;
      p += 3;
    } else if (p[0] == '{' && p[1] == '}' && next < LogRecord::max_args) {
      const LogArg& a = r.args[next++];
      char buf[64];
      switch (a.kind) {
        case LogArg::Kind::i64:
          std::snprintf(buf, sizeof buf, "%" PRId64, a.i);
          break;
        case LogArg::Kind::u64:
          std::snprintf(buf, sizeof buf, "%" PRIu64, a.u);
          break;
        case LogArg::Kind::f64:
          std::snprintf(buf, sizeof buf, "%g", a.f);
          break;
        case LogArg::Kind::text:
          out += a.s != nullptr ? a.s : "(null)";
          buf[0] = '\0';
          break;
        case LogArg::Kind::none:
          std::snprintf(buf, sizeof buf, "{}");
          break;
      }
      out += buf;
      ++p;
    } else {
      out += *p;
    }
  }
  return out;
}

LogDrain::LogDrain(Sink sink) : sink_(std::move(sink)) {
  if (!sink_) sink_ = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  thread_ = std::thread([this] {
    while (!stop_.load(std::memory_order_acquire)) {
      drain_once();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));  // non-RT thread: polling is fine
    }
  });
}

LogDrain::~LogDrain() {
  stop_.store(true, std::memory_order_release);
  thread_.join();
  drain_once();
}

void LogDrain::drain_once() {
  LogRecord r;
  while (log_ring().pop(r)) sink_(format_log_record(r));
  const auto dropped = log_ring().dropped();
  if (dropped != dropped_reported_) {
    sink_("[log] " + std::to_string(dropped - dropped_reported_) +
          " records dropped: the RT log ring was full");
    dropped_reported_ = dropped;
  }
}

}  // namespace saw
