// can-utils' text forms of a frame: cansend's `123#1122`, candump -L's `(1700000000.123456) can0 123#1122`.
#pragma once

#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

#include "saw/can/frame.hpp"

namespace saw::can {

// A frame as cansend takes it and candump -L prints it:
//   123#11223344          classic, 11-bit identifier (3 hex digits), data as hex bytes
//   1ABCDEF0#             classic, 29-bit identifier (8 hex digits), no data
//   123#R   123#R5        remote request, optionally with its length
//   123##1AABBCC          CAN FD: `##`, a flags digit (1 = BRS, 2 = ESI), then the data
//   20000004#0004000000000000   an error frame (CAN_ERR_FLAG in its 8-digit identifier)
//   123#1122334455667788_E      classic with 8 bytes and a raw DLC of 9..15 (len8_dlc)
std::string format_frame(const Frame& f);
// Parses the forms above (bytes may be separated by '.'); nullopt and `error` on anything else.
std::optional<Frame> parse_frame(std::string_view text, std::string* error = nullptr);

// One line of a candump -L log. `time` is wall-clock ns since the epoch, as candump stamps it.
struct LogEntry {
  TimeNs time = 0;
  std::string interface;
  Frame frame;
};
std::string format_log_line(TimeNs time, std::string_view interface, const Frame& f);  // no newline
std::optional<LogEntry> parse_log_line(std::string_view line, std::string* error = nullptr);

// CLOCK_REALTIME minus CLOCK_MONOTONIC now, in ns: what turns a frame's time into a log's.
TimeNs wall_clock_offset() noexcept;

// Appends frames to a candump -L log file. Not for the RT cycle (stdio, allocation): for a
// logger thread or process. Times given as CLOCK_MONOTONIC are written as wall-clock time,
// with the offset between the two clocks taken when the writer opens.
class CandumpWriter {
 public:
  // Opens (truncates) `path`; throws std::runtime_error naming the file and the reason.
  // `interface` names the bus on lines that do not name one themselves.
  explicit CandumpWriter(const std::string& path, std::string interface = "can0");
  ~CandumpWriter();
  CandumpWriter(const CandumpWriter&) = delete;
  CandumpWriter& operator=(const CandumpWriter&) = delete;

  void write(const Received& r) { write_wall(r.time + monotonic_to_wall_, r.frame, interface_); }
  void write(const Received& r, std::string_view interface) {
    write_wall(r.time + monotonic_to_wall_, r.frame, interface);
  }
  void write_wall(TimeNs wall_time, const Frame& f, std::string_view interface);
  void flush();

 private:
  std::FILE* file_ = nullptr;
  std::string interface_;
  TimeNs monotonic_to_wall_ = 0;
};

}  // namespace saw::can
