// The socketcand protocol's raw-mode subset: parsing client elements, formatting server ones.
#include "saw/can/socketcand.hpp"

#include <array>
#include <cstdio>
#include <vector>

namespace saw::can::socketcand {
namespace {

bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
bool is_printable(char c) noexcept { return c >= 0x20 && c < 0x7F; }

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// A hex field of 1..max_digits digits.
std::optional<std::uint32_t> parse_hex(std::string_view t, std::size_t max_digits) noexcept {
  if (t.empty() || t.size() > max_digits) return std::nullopt;
  std::uint32_t v = 0;
  for (char c : t) {
    const int d = hex_value(c);
    if (d < 0) return std::nullopt;
    v = (v << 4) | static_cast<std::uint32_t>(d);
  }
  return v;
}

std::optional<std::uint32_t> parse_decimal(std::string_view t, std::size_t max_digits) noexcept {
  if (t.empty() || t.size() > max_digits) return std::nullopt;
  std::uint32_t v = 0;
  for (char c : t) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + static_cast<std::uint32_t>(c - '0');
  }
  return v;
}

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_space(s[i])) ++i;
    const std::size_t start = i;
    while (i < s.size() && !is_space(s[i])) ++i;
    if (i > start) tokens.push_back(s.substr(start, i - start));
  }
  return tokens;
}

// An identifier as socketcand reads it: 8 digits make it extended, fewer standard.
bool parse_id(std::string_view t, Frame& f, std::string& error) {
  if (t.size() == 8) {
    const auto v = parse_hex(t, 8);
    if (!v || *v > CAN_EFF_MASK) {
      error = "identifier '" + std::string(t) + "': 8 hex digits up to 1FFFFFFF expected";
      return false;
    }
    f.id = *v | CAN_EFF_FLAG;
    return true;
  }
  const auto v = parse_hex(t, 3);
  if (!v || *v > CAN_SFF_MASK) {
    error = "identifier '" + std::string(t) + "': 1 to 3 hex digits up to 7FF, or 8 up to 1FFFFFFF expected";
    return false;
  }
  f.id = *v;
  return true;
}

bool parse_bytes(std::span<const std::string_view> tokens, Frame& f, std::string& error) {
  if (tokens.size() != f.len) {
    error = "length " + std::to_string(f.len) + " but " + std::to_string(tokens.size()) + " data bytes";
    return false;
  }
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    const auto v = parse_hex(tokens[i], 2);
    if (!v) {
      error = "data byte '" + std::string(tokens[i]) + "': 1 or 2 hex digits expected";
      return false;
    }
    f.data[i] = static_cast<std::uint8_t>(*v);
  }
  return true;
}

void put_hex(std::string& s, std::uint32_t v, int digits) {
  constexpr char hex[] = "0123456789ABCDEF";
  for (int i = digits - 1; i >= 0; --i) s += hex[(v >> (4 * i)) & 0xF];
}

}  // namespace

std::optional<Command> parse_command(std::string_view element, std::string& error) {
  if (element.size() < 2 || element.front() != '<' || element.back() != '>') {
    error = "an element is '< command ... >'";
    return std::nullopt;
  }
  const auto tokens = split(element.substr(1, element.size() - 2));
  if (tokens.empty()) {
    error = "empty element";
    return std::nullopt;
  }
  const std::string_view name = tokens[0];
  const std::span<const std::string_view> args(tokens.data() + 1, tokens.size() - 1);
  const auto arity = [&](std::size_t n) {
    if (args.size() == n) return true;
    error = "'" + std::string(name) + "' takes " + std::to_string(n) + " argument" + (n == 1 ? "" : "s");
    return false;
  };
  Command c;
  if (name == "open") {
    if (!arity(1)) return std::nullopt;
    c.kind = Command::Kind::open;
    c.bus = std::string(args[0]);
    return c;
  }
  if (name == "rawmode" || name == "bcmmode" || name == "echo") {
    if (!arity(0)) return std::nullopt;
    c.kind = name == "rawmode" ? Command::Kind::rawmode
                               : (name == "bcmmode" ? Command::Kind::bcmmode : Command::Kind::echo);
    return c;
  }
  if (name == "send" || name == "sendrtr") {
    const bool rtr = name == "sendrtr";
    if (args.size() < 2) {
      error =
          "'" + std::string(name) + "' takes an identifier, a length" + (rtr ? "" : " and the data bytes");
      return std::nullopt;
    }
    c.kind = Command::Kind::send;
    if (!parse_id(args[0], c.frame, error)) return std::nullopt;
    // socketcand reads the length as decimal and python-can writes it as hex: the same for 0-8.
    const auto len = parse_decimal(args[1], 1);
    if (!len || *len > CAN_MAX_DLEN) {
      error = "length '" + std::string(args[1]) + "': 0 to 8 expected";
      return std::nullopt;
    }
    c.frame.len = static_cast<std::uint8_t>(*len);
    if (rtr) {
      if (!arity(2)) return std::nullopt;
      c.frame.id |= CAN_RTR_FLAG;
      return c;
    }
    if (!parse_bytes(args.subspan(2), c.frame, error)) return std::nullopt;
    return c;
  }
  if (name == "fdsend") {
    if (args.size() < 3) {
      error = "'fdsend' takes an identifier, flags, a length and the data bytes";
      return std::nullopt;
    }
    c.kind = Command::Kind::send;
    if (!parse_id(args[0], c.frame, error)) return std::nullopt;
    const auto flags = parse_hex(args[1], 2);
    if (!flags || (*flags & ~static_cast<std::uint32_t>(CANFD_BRS | CANFD_ESI | CANFD_FDF)) != 0) {
      error = "flags '" + std::string(args[1]) + "': hex, 1 BRS, 2 ESI, 4 FDF";
      return std::nullopt;
    }
    const auto len = parse_decimal(args[2], 2);
    if (!len || !valid_length(static_cast<std::uint8_t>(*len), true)) {
      error = "length '" + std::string(args[2]) + "': 0 to 8, 12, 16, 20, 24, 32, 48 or 64 expected";
      return std::nullopt;
    }
    c.frame.flags = static_cast<std::uint8_t>(*flags | CANFD_FDF);
    c.frame.len = static_cast<std::uint8_t>(*len);
    if (!parse_bytes(args.subspan(3), c.frame, error)) return std::nullopt;
    return c;
  }
  static constexpr std::array<std::string_view, 13> not_here = {
      "add",        "update",      "delete",    "filter",    "muxfilter", "subscribe", "unsubscribe",
      "statistics", "controlmode", "isotpmode", "isotpconf", "sendpdu",   "B"};
  for (const auto n : not_here)
    if (name == n) {
      error = "'" + std::string(name) + "' is not supported by saw-socketcand (raw mode only)";
      return std::nullopt;
    }
  error = "unknown command '" + std::string(name.substr(0, 32)) + "'";
  return std::nullopt;
}

std::string format_frame(const Frame& f, TimeNs wall_time) {
  if (wall_time < 0) wall_time = 0;
  char stamp[48];
  std::snprintf(stamp, sizeof stamp, "%lld.%06lld", static_cast<long long>(wall_time / 1'000'000'000),
                static_cast<long long>(wall_time % 1'000'000'000 / 1000));
  std::string s;
  s.reserve(48 + 2 * f.len);
  s += f.fd() ? "< fdframe " : (f.remote() ? "< rtr " : "< frame ");
  if (f.extended())
    put_hex(s, f.id & CAN_EFF_MASK, 8);
  else
    put_hex(s, f.id & CAN_SFF_MASK, 3);
  s += ' ';
  if (f.fd()) {
    put_hex(s, f.flags, 2);
    s += ' ';
  }
  s += stamp;
  s += ' ';
  if (f.remote()) {
    s += std::to_string(f.len);
    s += " >";
    return s;
  }
  // Data as one run of hex digits, as socketcand writes it and python-can reads it.
  const std::size_t len = std::min<std::size_t>(f.len, CANFD_MAX_DLEN);
  for (std::size_t i = 0; i < len; ++i) put_hex(s, f.data[i], 2);
  s += " >";
  return s;
}

std::string format_error(std::string_view what) {
  std::string s = "< error ";
  for (char c : what.substr(0, 200))
    if (is_printable(c) && c != '<' && c != '>') s += c;
  s += " >";
  return s;
}

std::optional<std::string> Framer::next(std::string& error) {
  error.clear();
  if (discarding_) {  // the rest of an over-long element
    const auto close = buffer_.find('>');
    if (close == std::string::npos) {
      buffer_.clear();
      return std::nullopt;
    }
    buffer_.erase(0, close + 1);
    discarding_ = false;
  }
  std::size_t i = 0;
  while (i < buffer_.size() && is_space(buffer_[i])) ++i;
  if (i == buffer_.size()) {
    buffer_.clear();
    return std::nullopt;
  }
  if (buffer_[i] != '<') {
    const auto open = buffer_.find('<', i);
    buffer_.erase(0, open == std::string::npos ? buffer_.size() : open);
    error = "data outside '< >'";
    return std::nullopt;
  }
  for (std::size_t j = i + 1; j < buffer_.size(); ++j) {
    const char c = buffer_[j];
    if (j - i >= max_element) {
      buffer_.erase(0, j);  // the rest, up to its '>', goes next time
      discarding_ = true;
      error = "element longer than " + std::to_string(max_element) + " bytes";
      return std::nullopt;
    }
    if (c == '>') {
      std::string element = buffer_.substr(i, j - i + 1);
      buffer_.erase(0, j + 1);
      return element;
    }
    if (c == '<') {
      buffer_.erase(0, j);
      error = "'<' inside an element";
      return std::nullopt;
    }
    if (!is_printable(c) && !is_space(c)) {
      const auto open = buffer_.find('<', j);
      buffer_.erase(0, open == std::string::npos ? buffer_.size() : open);
      error = "control character in an element";
      return std::nullopt;
    }
  }
  return std::nullopt;
}

}  // namespace saw::can::socketcand
