// wait_for: polls a condition until it holds or a deadline passes.
#pragma once

#include <chrono>
#include <thread>

namespace saw::testing {

// True once done() holds; false if `limit` passes first. The limit is a generous bound, never a
// timing claim: the test asserts on what happened, and a slow machine only makes it wait longer.
template <class Done>
[[nodiscard]] bool wait_for(Done done, std::chrono::milliseconds limit = std::chrono::seconds(10),
                            std::chrono::milliseconds poll = std::chrono::milliseconds(1)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(poll);
  }
  return true;
}

}  // namespace saw::testing
