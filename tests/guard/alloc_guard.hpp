// AllocGuard: counts heap allocations and mutex locks made by threads inside an RT path.
#pragma once

#include <cstddef>
#include <cstdint>

namespace saw::testing {

struct GuardCounts {
  std::uint64_t allocations = 0;
  std::uint64_t locks = 0;
  std::size_t first_allocation_size = 0;
};

// Counts since the last reset(), made while saw::in_rt_context() was true.
GuardCounts guard_counts() noexcept;
void guard_reset() noexcept;

}  // namespace saw::testing
