// LatencyHistogram: wake-up latencies in 1 µs bins, written by one thread, read by any.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <ostream>
#include <span>
#include <string>

#include "saw/clock.hpp"

namespace saw {

class LatencyHistogram {
 public:
  explicit LatencyHistogram(std::size_t bins = 1000);

  // Writer (the task's thread), RT-safe.
  void record(TimeNs latency) noexcept {
    const auto us = static_cast<std::uint64_t>(latency < 0 ? 0 : latency / 1000);
    auto& cell = us < bins_ ? counts_[us] : overflows_;
    bump(cell);
    bump(total_);
    sum_ns_.store(
        sum_ns_.load(std::memory_order_relaxed) + static_cast<std::uint64_t>(latency < 0 ? 0 : latency),
        std::memory_order_relaxed);
    if (latency > max_.load(std::memory_order_relaxed)) max_.store(latency, std::memory_order_relaxed);
    if (latency < min_.load(std::memory_order_relaxed)) min_.store(latency, std::memory_order_relaxed);
  }
  void reset() noexcept;

  std::size_t bins() const noexcept { return bins_; }
  std::uint64_t count(std::size_t bin) const noexcept { return counts_[bin].load(std::memory_order_relaxed); }
  std::uint64_t overflows() const noexcept { return overflows_.load(std::memory_order_relaxed); }
  std::uint64_t total() const noexcept { return total_.load(std::memory_order_relaxed); }
  TimeNs min() const noexcept { return total() ? min_.load(std::memory_order_relaxed) : 0; }
  TimeNs max() const noexcept { return max_.load(std::memory_order_relaxed); }
  double mean() const noexcept;
  // Latency (ns, bin upper edge) below which a fraction q of samples fall; max() past the bins.
  TimeNs percentile(double q) const noexcept;

 private:
  static void bump(std::atomic<std::uint64_t>& a) noexcept {
    a.store(a.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }

  std::size_t bins_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> counts_;
  std::atomic<std::uint64_t> overflows_{0}, total_{0}, sum_ns_{0};
  std::atomic<TimeNs> min_{INT64_MAX}, max_{0};
};

// Writes histograms side by side in cyclictest's `-h` text format (one column per histogram).
void write_cyclictest_histogram(std::ostream& os, std::span<const LatencyHistogram* const> hs);

}  // namespace saw
