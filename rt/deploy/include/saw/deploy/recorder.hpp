// Recorder: writes selected state-table columns to CSV from a non-RT thread, reading history.
#pragma once

#include <atomic>
#include <cstdio>
#include <functional>
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
// side: it only reads state-table history. If it falls more than a ring behind, it counts the
// rows it lost and says so (lost_rows()).
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
  void start_thread();  // polls every 10 ms until stop()
  void stop();          // final poll, flush, close
  std::uint64_t rows() const noexcept { return rows_; }
  std::uint64_t lost_rows() const noexcept { return lost_; }
  const std::string& path() const noexcept { return path_; }

 private:
  std::string path_;
  std::vector<Column> columns_;
  int decimation_;
  std::FILE* file_ = nullptr;
  std::uint64_t next_tick_ = 0, rows_ = 0, lost_ = 0;
  std::vector<unsigned char> buffer_;
  std::string line_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace saw::deploy
