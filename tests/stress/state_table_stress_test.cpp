// One writer at full speed, several readers checking that every row they read is whole.
// Run under the tsan preset in CI: every access to shared rows must be race-free.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <thread>
#include <vector>

#include "saw/state_table.hpp"

namespace {

// Every field derives from one counter, so a torn row shows as a mismatch.
struct Sample {
  std::uint64_t k = 0;
  std::uint64_t not_k = ~0ULL;
  std::array<double, 6> values{};
};

bool whole(const Sample& s) {
  if (s.not_k != ~s.k) return false;
  for (std::size_t i = 0; i < s.values.size(); ++i)
    if (s.values[i] != static_cast<double>(s.k) + static_cast<double>(i)) return false;
  return true;
}

constexpr std::uint64_t rows_to_write = 200'000;

TEST(StateTableStress, ReadersOnlyEverSeeWholeRows) {
  Sample source;
  std::uint64_t counter = 0;
  saw::StateTable table(64);  // small ring: readers are lapped often
  const auto col = table.add_column("sample", &source);
  const auto ctr = table.add_column("counter", &counter);
  table.finalize();

  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> torn{0}, reads{0}, history_reads{0}, time_reads{0}, backwards{0};
  auto reader = [&](int mode) {
    std::uint64_t last_k = 0;
    std::array<Sample, 16> history;
    while (!done.load(std::memory_order_acquire)) {
      Sample s;
      saw::RowStamp stamp;
      if (mode == 0) {
        if (table.read_latest(col, s, &stamp) != saw::Status::ok) continue;
        if (!whole(s) || s.k != stamp.tick + 1) torn.fetch_add(1);
        if (s.k < last_k) backwards.fetch_add(1);
        last_k = s.k;
        std::uint64_t c = 0;
        if (table.read_latest(ctr, c) == saw::Status::ok && c < s.k) backwards.fetch_add(1);
        reads.fetch_add(1, std::memory_order_relaxed);
      } else if (mode == 1) {
        const auto n = table.read_history(col, std::span<Sample>(history));
        for (std::size_t i = 0; i < n; ++i) {
          if (!whole(history[i])) torn.fetch_add(1);
          if (i > 0 && history[i].k <= history[i - 1].k) backwards.fetch_add(1);
        }
        history_reads.fetch_add(1, std::memory_order_relaxed);
      } else {
        const auto latest = table.rows_written();
        if (latest < 10) continue;
        const auto t = static_cast<saw::TimeNs>(latest - 5) * 10;  // the writer stamps tick*10
        const auto status = table.read_at_or_before(col, t + 5, s, &stamp);
        if (status == saw::Status::ok) {
          if (!whole(s) || stamp.time > t + 5) torn.fetch_add(1);
          time_reads.fetch_add(1, std::memory_order_relaxed);
        }
      }
    }
  };
  std::vector<std::thread> readers;
  for (int i = 0; i < 3; ++i) readers.emplace_back(reader, i);

  // Write at least rows_to_write rows, and on until every reader has done real work (readers
  // may be scheduled late on a loaded machine); bounded, so a broken reader cannot hang CI.
  const auto readers_busy = [&] {
    return reads.load() >= 1000 && history_reads.load() >= 100 && time_reads.load() >= 1000;
  };
  std::uint64_t last_k = 0;
  for (std::uint64_t k = 1; k <= rows_to_write || (!readers_busy() && k <= 100 * rows_to_write); ++k) {
    last_k = k;
    source.k = k;
    source.not_k = ~k;
    for (std::size_t i = 0; i < source.values.size(); ++i)
      source.values[i] = static_cast<double>(k) + static_cast<double>(i);
    counter = k;
    table.advance(static_cast<saw::TimeNs>(k - 1) * 10);
  }
  done.store(true, std::memory_order_release);
  for (auto& t : readers) t.join();

  EXPECT_EQ(torn.load(), 0u);
  EXPECT_EQ(backwards.load(), 0u);
  EXPECT_TRUE(readers_busy()) << "reads " << reads.load() << ", history " << history_reads.load()
                              << ", by time " << time_reads.load();
  Sample last;
  ASSERT_EQ(table.read_latest(col, last), saw::Status::ok);
  EXPECT_EQ(last.k, last_k);
}

}  // namespace
