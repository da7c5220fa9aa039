// Recorder: writes selected state-table columns to CSV from a non-RT thread, reading history.
#pragma once

#include <atomic>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "saw/component.hpp"

namespace saw::deploy {

// Turns one value (its bytes) into CSV cells; `names` gives each cell's suffix.
struct ColumnFormat {
  std::vector<std::string> names;
  std::function<void(const void* value, std::string& out)> write;
};

// The formatter for a state-table column type, or nullptr if the type is not known.
const ColumnFormat* format_for(TypeInfo type);

// The first column's component sets the row clock: one CSV row per row of its state table;
// the other columns are read at or before that row's time. The recorder never blocks the RT
// side: it only reads state-table history. Running, it is two threads: a collector that copies
// each new row (as CSV text) out of the history every 10 ms, at the lowest SCHED_FIFO priority
// where it may (below every task, above any normal process: a loaded machine does not starve
// it past the ring), and a writer that gives them to the file (a slow disk delays the writer,
// not the collector). If the collector falls more than a ring behind, or the writer more than
// `max_pending` bytes, it counts the rows it lost and says so (lost_rows()).
class Recorder {
 public:
  struct Column {
    const Component* component;
    std::uint32_t index;
    const ColumnFormat* format;
    std::string name;  // component.column
  };

  Recorder(std::string path, std::vector<Column> columns, int decimation = 1);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Writes the rows written since the last poll (stepped mode calls it; the thread otherwise).
  void poll();
  void start_thread();  // collects every 10 ms and writes behind, until stop()
  void stop();          // final poll, flush, close
  std::uint64_t rows() const noexcept { return rows_.load(std::memory_order_relaxed); }
  std::uint64_t lost_rows() const noexcept { return lost_.load(std::memory_order_relaxed); }

  static constexpr std::size_t max_pending = std::size_t{64} << 20;  // bytes the writer may lag
  const std::string& path() const noexcept { return path_; }

 private:
  std::string path_;
  std::vector<Column> columns_;
  int decimation_;
  // Appends the rows written since the last call to `out` (CSV lines); counts lost ones.
  void collect(std::string& out);
  void write_pending();

  std::FILE* file_ = nullptr;
  std::uint64_t next_tick_ = 0;
  std::atomic<std::uint64_t> rows_{0}, lost_{0};
  std::vector<unsigned char> buffer_;
  std::string line_, collected_;
  std::mutex pending_mutex_;
  std::string pending_;  // collected, not yet written (guarded by pending_mutex_)
  std::atomic<bool> stop_{false};
  std::thread collector_, writer_;
};

}  // namespace saw::deploy
