// StateTable: a component's ring of state rows, one per cycle, written by its owner only.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "saw/clock.hpp"
#include "saw/status.hpp"
#include "saw/type_info.hpp"

namespace saw {

// Tick and time of the row a value came from.
struct RowStamp {
  std::uint64_t tick = 0;
  TimeNs time = 0;
};

// Handle to one column; cheap to copy, valid for the table's lifetime.
template <Plain T>
struct StateColumn {
  const class StateTable* table = nullptr;
  std::uint32_t index = 0;
};

// What a column is for besides its history: a `summary` column is also reported when a run
// ends (saw-rt prints its latest value with the formatter its package registered).
enum class ColumnUse : std::uint8_t { history, summary };

// Every row holds all columns of one cycle plus its tick and time. Each row carries its own
// sequence number (a seqlock): the writer makes it odd, stores, makes it even with release;
// a reader copies the row between two loads of that number and retries if it changed. All
// row words are std::atomic, so there is no data race anywhere, only a retry.
class StateTable {
 public:
  static constexpr std::size_t default_rows = 256;

  explicit StateTable(std::size_t rows = default_rows);
  ~StateTable();
  StateTable(const StateTable&) = delete;
  StateTable& operator=(const StateTable&) = delete;

  // Setup (before finalize): each advance() copies *source into the new row.
  template <Plain T>
  StateColumn<T> add_column(std::string name, const T* source, ColumnUse use = ColumnUse::history) {
    return {this, add_column_erased(std::move(name), type_info_of<T>(), source, use)};
  }
  // For components built from a description (a gateway's mirror of a remote component): a
  // column of a type known at run time; `source` holds type.size bytes.
  std::uint32_t add_column_erased(std::string name, TypeInfo type, const void* source,
                                  ColumnUse use = ColumnUse::history);
  // Allocates the rows; no column may be added after this.
  void finalize();
  bool finalized() const noexcept { return rows_ != nullptr; }

  // Writer, RT-safe: snapshots every column's source into the next row, stamped with time.
  void advance(TimeNs time) noexcept;

  // Readers, any thread, wait-free unless the writer is overwriting the very row read.
  template <Plain T>
  Status read_latest(StateColumn<T> c, T& out, RowStamp* stamp = nullptr) const noexcept {
    return read_latest_erased(c.index, &out, stamp);
  }
  template <Plain T>
  Status read_tick(StateColumn<T> c, std::uint64_t tick, T& out) const noexcept {
    return read_row(c.index, tick, &out, nullptr);
  }
  // The newest row whose time is at or before t.
  template <Plain T>
  Status read_at_or_before(StateColumn<T> c, TimeNs t, T& out, RowStamp* stamp = nullptr) const noexcept {
    return read_at_or_before_erased(c.index, t, &out, stamp);
  }
  // Up to out.size() most recent values, oldest first; returns how many were written.
  template <Plain T>
  std::size_t read_history(StateColumn<T> c, std::span<T> out,
                           std::span<RowStamp> stamps = {}) const noexcept {
    return read_history_erased(c.index, out.data(), sizeof(T), out.size(), stamps);
  }

  // Type-erased forms, for commands bound at run time and for recorders.
  Status read_tick_erased(std::uint32_t column, std::uint64_t tick, void* out,
                          RowStamp* stamp) const noexcept {
    return read_row(column, tick, out, stamp);
  }
  Status read_latest_erased(std::uint32_t column, void* out, RowStamp* stamp) const noexcept;
  Status read_at_or_before_erased(std::uint32_t column, TimeNs t, void* out, RowStamp* stamp) const noexcept;
  std::size_t read_history_erased(std::uint32_t column, void* out, std::size_t stride, std::size_t n,
                                  std::span<RowStamp> stamps) const noexcept;

  // Number of rows written so far; the newest row's tick is rows_written() - 1.
  std::uint64_t rows_written() const noexcept { return written_.load(std::memory_order_acquire); }
  std::size_t capacity() const noexcept { return capacity_; }
  std::size_t column_count() const noexcept { return columns_.size(); }
  const std::string& column_name(std::uint32_t c) const { return columns_[c].name; }
  TypeInfo column_type(std::uint32_t c) const { return columns_[c].type; }
  ColumnUse column_use(std::uint32_t c) const { return columns_[c].use; }
  // Column index by name, or -1.
  int find_column(std::string_view name) const noexcept;

 private:
  struct Column {
    std::string name;
    TypeInfo type;
    const void* source;
    std::size_t word_offset;
    std::size_t words;
    ColumnUse use;
  };
  // Row word layout: [seq, tick, time, column words...].
  static constexpr std::size_t seq_word = 0, tick_word = 1, time_word = 2, header_words = 3;

  Status read_row(std::uint32_t column, std::uint64_t tick, void* out, RowStamp* stamp) const noexcept;
  // Time of row `tick`, or -1 if that row is gone or being written.
  bool row_time(std::uint64_t tick, TimeNs& time) const noexcept;
  std::atomic<std::uint64_t>* row(std::uint64_t tick) const noexcept {
    return rows_.get() + (tick % capacity_) * row_words_;
  }

  std::size_t capacity_;
  std::vector<Column> columns_;
  std::size_t row_words_ = header_words;
  std::unique_ptr<std::atomic<std::uint64_t>[]> rows_;
  std::unique_ptr<std::uint64_t[]> scratch_;  // writer's staging copy of the sources
  std::atomic<std::uint64_t> written_{0};
};

}  // namespace saw
