#include "saw/latency_histogram.hpp"

#include <algorithm>
#include <cstdio>

namespace saw {

LatencyHistogram::LatencyHistogram(std::size_t bins)
    : bins_(bins), counts_(std::make_unique<std::atomic<std::uint64_t>[]>(bins)) {
  reset();
}

void LatencyHistogram::reset() noexcept {
  for (std::size_t i = 0; i < bins_; ++i) counts_[i].store(0, std::memory_order_relaxed);
  overflows_.store(0, std::memory_order_relaxed);
  total_.store(0, std::memory_order_relaxed);
  sum_ns_.store(0, std::memory_order_relaxed);
  min_.store(INT64_MAX, std::memory_order_relaxed);
  max_.store(0, std::memory_order_relaxed);
}

double LatencyHistogram::mean() const noexcept {
  const auto n = total();
  return n ? static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) / static_cast<double>(n) : 0.0;
}

TimeNs LatencyHistogram::percentile(double q) const noexcept {
  const auto n = total();
  if (n == 0) return 0;
  const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(n) + 0.5);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins_; ++i) {
    seen += count(i);
    if (seen >= rank && seen > 0) return static_cast<TimeNs>(i + 1) * 1000;
  }
  return max();
}

void write_cyclictest_histogram(std::ostream& os, std::span<const LatencyHistogram* const> hs) {
  char buf[64];
  const std::size_t bins = hs.empty() ? 0 : hs.front()->bins();
  os << "# Histogram\n";
  for (std::size_t i = 0; i < bins; ++i) {
    std::snprintf(buf, sizeof buf, "%06zu", i);
    os << buf;
    for (const auto* h : hs) {
      std::snprintf(buf, sizeof buf, " %06llu",
                    static_cast<unsigned long long>(i < h->bins() ? h->count(i) : 0));
      os << buf;
    }
    os << '\n';
  }
  const auto row = [&](const char* label, auto value) {
    os << label;
    for (const auto* h : hs) {
      std::snprintf(buf, sizeof buf, " %05llu", static_cast<unsigned long long>(value(*h)));
      os << buf;
    }
    os << '\n';
  };
  os << "# Total:";
  for (const auto* h : hs) {
    std::snprintf(buf, sizeof buf, " %09llu", static_cast<unsigned long long>(h->total()));
    os << buf;
  }
  os << '\n';
  row("# Min Latencies:", [](const LatencyHistogram& h) { return h.min() / 1000; });
  row("# Avg Latencies:", [](const LatencyHistogram& h) { return static_cast<TimeNs>(h.mean() / 1000); });
  row("# Max Latencies:", [](const LatencyHistogram& h) { return h.max() / 1000; });
  row("# Histogram Overflows:", [](const LatencyHistogram& h) { return h.overflows(); });
}

}  // namespace saw
