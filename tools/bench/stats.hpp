// Sample statistics for benchmarks: median and tail percentiles of latencies in nanoseconds.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace saw::bench {

struct Summary {
  double median_us = 0, p90_us = 0, p99_us = 0, p999_us = 0, max_us = 0;
  std::size_t n = 0;
};

// Sorts `samples` in place.
inline Summary summarize(std::vector<std::int64_t>& samples) {
  Summary s;
  s.n = samples.size();
  if (samples.empty()) return s;
  std::sort(samples.begin(), samples.end());
  const auto at = [&](double q) {
    const auto i = static_cast<std::size_t>(q * static_cast<double>(samples.size() - 1) + 0.5);
    return static_cast<double>(samples[i]) / 1e3;
  };
  s.median_us = at(0.5);
  s.p90_us = at(0.9);
  s.p99_us = at(0.99);
  s.p999_us = at(0.999);
  s.max_us = static_cast<double>(samples.back()) / 1e3;
  return s;
}

inline void print_row(bool markdown, const std::string& name, const Summary& s) {
  if (markdown)
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %zu |\n", name.c_str(), s.median_us, s.p99_us, s.p999_us,
                s.max_us, s.n);
  else
    std::printf("%-44s median %9.3f  p99 %9.3f  p99.9 %9.3f  max %10.3f us  (n=%zu)\n", name.c_str(),
                s.median_us, s.p99_us, s.p999_us, s.max_us, s.n);
}

inline void print_header(bool markdown) {
  if (markdown)
    std::printf("| case | median µs | p99 µs | p99.9 µs | max µs | n |\n|---|---|---|---|---|---|\n");
}

}  // namespace saw::bench
