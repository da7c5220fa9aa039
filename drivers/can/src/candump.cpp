// can-utils' frame and log-line text forms, written and parsed.
#include "saw/can/candump.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <limits>
#include <stdexcept>

namespace saw::can {
namespace {

constexpr char hex_digits[] = "0123456789ABCDEF";

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

void put_hex(std::string& s, std::uint64_t v, int digits) {
  for (int i = digits - 1; i >= 0; --i) s += hex_digits[(v >> (4 * i)) & 0xF];
}

std::optional<Frame> fail(std::string* error, std::string what) {
  if (error != nullptr) *error = std::move(what);
  return std::nullopt;
}

}  // namespace

std::string format_frame(const Frame& f) {
  std::string s;
  s.reserve(16 + 2 * f.len);
  if (f.error())
    put_hex(s, f.id & (CAN_ERR_FLAG | CAN_ERR_MASK), 8);
  else if (f.extended())
    put_hex(s, f.id & CAN_EFF_MASK, 8);
  else
    put_hex(s, f.id & CAN_SFF_MASK, 3);
  s += '#';
  if (f.fd()) {
    s += '#';
    s += hex_digits[f.flags & (CANFD_BRS | CANFD_ESI)];
  } else if (f.remote()) {
    s += 'R';
    if (f.len > 0 && f.len <= CAN_MAX_DLEN) s += hex_digits[f.len];
    return s;
  }
  const std::size_t len = std::min<std::size_t>(f.len, CANFD_MAX_DLEN);
  for (std::size_t i = 0; i < len; ++i) put_hex(s, f.data[i], 2);
  if (!f.fd() && f.len == CAN_MAX_DLEN && f.reserved1 > CAN_MAX_DLEN && f.reserved1 <= 15) {
    s += '_';
    s += hex_digits[f.reserved1];
  }
  return s;
}

std::optional<Frame> parse_frame(std::string_view text, std::string* error) {
  const auto hash = text.find('#');
  if (hash == std::string_view::npos) return fail(error, "no '#' between identifier and data");
  const std::string_view id_text = text.substr(0, hash);
  if (id_text.size() != 3 && id_text.size() != 8)
    return fail(error,
                "identifier '" + std::string(id_text) + "': 3 hex digits (11-bit) or 8 (29-bit) expected");
  std::uint32_t id = 0;
  for (char c : id_text) {
    const int v = hex_value(c);
    if (v < 0) return fail(error, "identifier '" + std::string(id_text) + "' is not hexadecimal");
    id = (id << 4) | static_cast<std::uint32_t>(v);
  }
  Frame f;
  if (id_text.size() == 3) {
    if (id > CAN_SFF_MASK) return fail(error, "11-bit identifier " + std::string(id_text) + " is above 7FF");
    f.id = id;
  } else if ((id & CAN_ERR_FLAG) != 0) {
    if ((id & ~(CAN_ERR_FLAG | CAN_ERR_MASK)) != 0)
      return fail(error, "error frame identifier " + std::string(id_text) + " has bits above 3FFFFFFF");
    // The error classes are bits 0..9 (linux/can/error.h); well_formed(), the check every frame
    // from outside passes, takes no identifier bit above the 11th without CAN_EFF_FLAG.
    if ((id & CAN_ERR_MASK & ~CAN_SFF_MASK) != 0)
      return fail(error,
                  "error frame identifier " + std::string(id_text) + " has error class bits above 7FF");
    f.id = id;
  } else {
    if (id > CAN_EFF_MASK)
      return fail(error, "29-bit identifier " + std::string(id_text) + " is above 1FFFFFFF");
    f.id = id | CAN_EFF_FLAG;
  }
  std::string_view rest = text.substr(hash + 1);
  std::size_t max_len = CAN_MAX_DLEN;
  if (!rest.empty() && rest.front() == '#') {
    if (f.error()) return fail(error, "an error frame cannot be CAN FD");
    if (rest.size() < 2) return fail(error, "CAN FD frame without its flags digit after '##'");
    const int flags = hex_value(rest[1]);
    if (flags < 0 || (flags & ~(CANFD_BRS | CANFD_ESI | CANFD_FDF)) != 0)
      return fail(error,
                  std::string("CAN FD flags digit '") + rest[1] + "': 0 to 7 expected (1 BRS, 2 ESI, 4 FDF)");
    f.flags = static_cast<std::uint8_t>(flags | CANFD_FDF);
    max_len = CANFD_MAX_DLEN;
    rest.remove_prefix(2);
  } else if (!rest.empty() && (rest.front() == 'R' || rest.front() == 'r')) {
    if (f.error()) return fail(error, "an error frame cannot be a remote request");
    f.id |= CAN_RTR_FLAG;
    rest.remove_prefix(1);
    if (rest.empty()) return f;
    const int len = hex_value(rest.front());
    if (rest.size() != 1 || len < 0 || len > static_cast<int>(CAN_MAX_DLEN))
      return fail(error, "remote request length '" + std::string(rest) + "': one digit 0 to 8 expected");
    f.len = static_cast<std::uint8_t>(len);
    return f;
  }
  std::size_t len = 0;
  while (!rest.empty()) {
    if (rest.front() == '.') {
      rest.remove_prefix(1);
      continue;
    }
    if (rest.front() == '_') break;
    if (rest.size() < 2 || hex_value(rest[0]) < 0 || hex_value(rest[1]) < 0)
      return fail(error, "data '" + std::string(rest) + "': whole hex bytes expected");
    if (len == max_len) return fail(error, "more than " + std::to_string(max_len) + " data bytes");
    f.data[len++] = static_cast<std::uint8_t>(hex_value(rest[0]) << 4 | hex_value(rest[1]));
    rest.remove_prefix(2);
  }
  f.len = static_cast<std::uint8_t>(len);
  if (!rest.empty()) {  // `_<dlc>`: a classic frame's raw DLC beyond 8
    const int dlc = rest.size() == 2 ? hex_value(rest[1]) : -1;
    if (f.fd() || len != CAN_MAX_DLEN || dlc <= static_cast<int>(CAN_MAX_DLEN))
      return fail(error,
                  "'" + std::string(rest) + "': a raw DLC (_9 to _F) follows only 8 classic data bytes");
    f.reserved1 = static_cast<std::uint8_t>(dlc);
  }
  if (f.fd() && !valid_length(f.len, true))
    return fail(error,
                "CAN FD frames carry 0 to 8, 12, 16, 20, 24, 32, 48 or 64 bytes, not " + std::to_string(len));
  return f;
}

std::string format_log_line(TimeNs time, std::string_view interface, const Frame& f) {
  if (time < 0) time = 0;
  char stamp[40];
  std::snprintf(stamp, sizeof stamp, "(%010lld.%06lld) ", static_cast<long long>(time / 1'000'000'000),
                static_cast<long long>(time % 1'000'000'000 / 1000));
  std::string s = stamp;
  s += interface;
  s += ' ';
  s += format_frame(f);
  return s;
}

std::optional<LogEntry> parse_log_line(std::string_view line, std::string* error) {
  const auto failed = [&](std::string what) -> std::optional<LogEntry> {
    if (error != nullptr) *error = std::move(what);
    return std::nullopt;
  };
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' '))
    line.remove_suffix(1);
  if (line.empty() || line.front() != '(') return failed("a log line starts with '(seconds.microseconds)'");
  const auto close = line.find(')');
  if (close == std::string_view::npos) return failed("no ')' after the time stamp");
  const std::string_view stamp = line.substr(1, close - 1);
  const auto dot = stamp.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot > 12 || stamp.size() - dot - 1 != 6)
    return failed("time stamp '" + std::string(stamp) + "': seconds.microseconds (6 digits) expected");
  std::int64_t secs = 0, usecs = 0;
  for (std::size_t i = 0; i < stamp.size(); ++i) {
    if (i == dot) continue;
    const char c = stamp[i];
    if (c < '0' || c > '9') return failed("time stamp '" + std::string(stamp) + "' is not decimal");
    auto& v = i < dot ? secs : usecs;
    v = v * 10 + (c - '0');
  }
  // Up to 12 digits are read, but a TimeNs holds only 9223372035 s (year 2262) in nanoseconds.
  if (secs > (std::numeric_limits<TimeNs>::max() - 999'999'999) / 1'000'000'000)
    return failed("time stamp '" + std::string(stamp) + "' is beyond the year 2262");
  std::string_view rest = line.substr(close + 1);
  if (rest.empty() || rest.front() != ' ') return failed("a space expected after the time stamp");
  rest.remove_prefix(1);
  const auto space = rest.find(' ');
  if (space == 0 || space == std::string_view::npos)
    return failed("'interface frame' expected after the time stamp");
  LogEntry e;
  e.time = secs * 1'000'000'000 + usecs * 1000;
  e.interface = std::string(rest.substr(0, space));
  std::string why;
  const auto f = parse_frame(rest.substr(space + 1), &why);
  if (!f) return failed(why);
  e.frame = *f;
  return e;
}

TimeNs wall_clock_offset() noexcept {
  timespec wall{}, mono{};
  clock_gettime(CLOCK_REALTIME, &wall);
  clock_gettime(CLOCK_MONOTONIC, &mono);
  return (static_cast<TimeNs>(wall.tv_sec) - mono.tv_sec) * 1'000'000'000 + (wall.tv_nsec - mono.tv_nsec);
}

CandumpWriter::CandumpWriter(const std::string& path, std::string interface)
    : interface_(std::move(interface)) {
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) throw std::runtime_error("candump log " + path + ": " + std::strerror(errno));
  monotonic_to_wall_ = wall_clock_offset();
}

CandumpWriter::~CandumpWriter() {
  if (file_ != nullptr) std::fclose(file_);
}

void CandumpWriter::write_wall(TimeNs wall_time, const Frame& f, std::string_view interface) {
  const std::string line = format_log_line(wall_time, interface, f);
  std::fputs(line.c_str(), file_);
  std::fputc('\n', file_);
}

void CandumpWriter::flush() { std::fflush(file_); }

}  // namespace saw::can
