#include "saw/state_table.hpp"

#include <cstring>
#include <stdexcept>

namespace saw {
namespace {
constexpr int max_read_attempts = 64;
constexpr std::size_t word = sizeof(std::uint64_t);
}  // namespace

StateTable::StateTable(std::size_t rows) : capacity_(rows < 4 ? 4 : rows) {}
StateTable::~StateTable() = default;

std::uint32_t StateTable::add_column_erased(std::string name, TypeInfo type, const void* source,
                                            ColumnUse use) {
  if (finalized()) throw std::logic_error("state table: column '" + name + "' added after start");
  if (source == nullptr) throw std::invalid_argument("state table: column '" + name + "' has no source");
  if (find_column(name) >= 0) throw std::invalid_argument("state table: column '" + name + "' added twice");
  const std::size_t words = (type.size + word - 1) / word;
  columns_.push_back({std::move(name), type, source, row_words_, words, use});
  row_words_ += words;
  return static_cast<std::uint32_t>(columns_.size() - 1);
}

int StateTable::find_column(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < columns_.size(); ++i)
    if (columns_[i].name == name) return static_cast<int>(i);
  return -1;
}

void StateTable::finalize() {
  if (finalized()) return;
  rows_ = std::make_unique<std::atomic<std::uint64_t>[]>(capacity_ * row_words_);
  scratch_ = std::make_unique<std::uint64_t[]>(row_words_);
  for (std::size_t i = 0; i < capacity_ * row_words_; ++i) rows_[i].store(0, std::memory_order_relaxed);
}

void StateTable::advance(TimeNs time) noexcept {
  // Stage the sources first, so the row stays odd ("being written") for as short as possible.
  for (const auto& c : columns_) std::memcpy(&scratch_[c.word_offset], c.source, c.type.size);
  const std::uint64_t tick = written_.load(std::memory_order_relaxed);
  auto* r = row(tick);
  const auto seq = r[seq_word].load(std::memory_order_relaxed);
  // Fence-free seqlock (Boehm, "Can seqlocks get along with programming language memory
  // models?"): release stores of the data keep them after the odd seq for any reader whose
  // acquire load sees one of them. Plain MOVs on x86, and visible to ThreadSanitizer, which
  // does not model fences.
  r[seq_word].store(seq + 1, std::memory_order_relaxed);
  r[tick_word].store(tick, std::memory_order_release);
  r[time_word].store(static_cast<std::uint64_t>(time), std::memory_order_release);
  for (std::size_t w = header_words; w < row_words_; ++w) r[w].store(scratch_[w], std::memory_order_release);
  r[seq_word].store(seq + 2, std::memory_order_release);
  written_.store(tick + 1, std::memory_order_release);
}

Status StateTable::read_row(std::uint32_t column, std::uint64_t tick, void* out,
                            RowStamp* stamp) const noexcept {
  const Column& c = columns_[column];
  const auto* r = row(tick);
  std::uint64_t buffer[64];
  const bool small = c.words <= 64;
  for (int attempt = 0; attempt < max_read_attempts; ++attempt) {
    const auto s1 = r[seq_word].load(std::memory_order_acquire);
    if (s1 & 1U) continue;
    // Acquire loads of the data: if one saw a newer write, the seq reload below sees it changed.
    const auto row_tick = r[tick_word].load(std::memory_order_acquire);
    const auto row_time = r[time_word].load(std::memory_order_acquire);
    if (small) {
      for (std::size_t w = 0; w < c.words; ++w)
        buffer[w] = r[c.word_offset + w].load(std::memory_order_acquire);
    } else {
      auto* dst = static_cast<std::byte*>(out);
      for (std::size_t w = 0; w < c.words; ++w) {
        const auto v = r[c.word_offset + w].load(std::memory_order_acquire);
        std::memcpy(dst + w * word, &v, std::min(word, c.type.size - w * word));
      }
    }
    if (r[seq_word].load(std::memory_order_relaxed) != s1) continue;
    if (s1 == 0 || row_tick != tick) return Status::overwritten;
    if (small) std::memcpy(out, buffer, c.type.size);
    if (stamp != nullptr) *stamp = {row_tick, static_cast<TimeNs>(row_time)};
    return Status::ok;
  }
  return Status::busy;
}

Status StateTable::read_latest_erased(std::uint32_t column, void* out, RowStamp* stamp) const noexcept {
  for (int attempt = 0; attempt < max_read_attempts; ++attempt) {
    const auto n = written_.load(std::memory_order_acquire);
    if (n == 0) return Status::no_data;
    const Status s = read_row(column, n - 1, out, stamp);
    if (s != Status::overwritten) return s;  // lapped by the writer: take the newer row
  }
  return Status::busy;
}

bool StateTable::row_time(std::uint64_t tick, TimeNs& time) const noexcept {
  const auto* r = row(tick);
  for (int attempt = 0; attempt < max_read_attempts; ++attempt) {
    const auto s1 = r[seq_word].load(std::memory_order_acquire);
    if (s1 & 1U) continue;
    const auto row_tick = r[tick_word].load(std::memory_order_acquire);
    const auto t = r[time_word].load(std::memory_order_acquire);
    if (r[seq_word].load(std::memory_order_relaxed) != s1) continue;
    if (s1 == 0 || row_tick != tick) return false;
    time = static_cast<TimeNs>(t);
    return true;
  }
  return false;
}

Status StateTable::read_at_or_before_erased(std::uint32_t column, TimeNs t, void* out,
                                            RowStamp* stamp) const noexcept {
  const auto n = written_.load(std::memory_order_acquire);
  if (n == 0) return Status::no_data;
  // Keep one row of margin: the writer may be overwriting the oldest row right now.
  std::uint64_t lo = n > capacity_ - 1 ? n - (capacity_ - 1) : 0;
  std::uint64_t hi = n - 1;
  TimeNs time = 0;
  if (!row_time(lo, time)) return Status::overwritten;
  if (time > t) return Status::overwritten;  // t is older than the history kept
  // Binary search for the last row with time <= t in [lo, hi].
  while (lo < hi) {
    const std::uint64_t mid = lo + (hi - lo + 1) / 2;
    if (!row_time(mid, time)) return Status::overwritten;
    if (time <= t)
      lo = mid;
    else
      hi = mid - 1;
  }
  return read_row(column, lo, out, stamp);
}

std::size_t StateTable::read_history_erased(std::uint32_t column, void* out, std::size_t stride,
                                            std::size_t n, std::span<RowStamp> stamps) const noexcept {
  const auto written = written_.load(std::memory_order_acquire);
  const std::uint64_t available = written < capacity_ - 1 ? written : capacity_ - 1;
  const std::size_t count = n < available ? n : static_cast<std::size_t>(available);
  const std::uint64_t first = written - count;
  std::size_t got = 0;
  for (std::size_t i = 0; i < count; ++i) {
    RowStamp s;
    if (read_row(column, first + i, static_cast<std::byte*>(out) + got * stride, &s) != Status::ok)
      continue;  // overwritten meanwhile: only the rows still whole are returned
    if (got < stamps.size()) stamps[got] = s;
    ++got;
  }
  return got;
}

}  // namespace saw
