#include "saw/canopen/sim/fault.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "saw/canopen/cob.hpp"

namespace saw::canopen::sim {

namespace {

struct Name {
  FaultKind kind;
  std::string_view text;
};
constexpr Name names[] = {
    {FaultKind::over_current, "over-current"},     {FaultKind::following_error, "following-error"},
    {FaultKind::heartbeat_loss, "heartbeat-loss"}, {FaultKind::bus_off, "bus-off"},
    {FaultKind::sdo_abort, "sdo-abort"},
};

[[noreturn]] void fail(std::string_view text, const std::string& what) {
  throw std::invalid_argument("fault '" + std::string(text) + "': " + what);
}

// An unsigned integer in C notation (0x.. hex, else decimal), the whole of `s`.
std::optional<std::uint64_t> parse_unsigned(std::string_view s) {
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    s.remove_prefix(2);
    base = 16;
  }
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (s.empty() || ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
  return v;
}

// Seconds as a decimal number, 0 or more, at most a day.
std::optional<TimeNs> parse_seconds(std::string_view s) {
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc{} || end != s.data() + s.size() || !std::isfinite(v) || v < 0 || v > 86400)
    return std::nullopt;
  return static_cast<TimeNs>(std::llround(v * 1e9));
}

std::vector<std::string_view> split(std::string_view s, char c) {
  std::vector<std::string_view> parts;
  for (std::size_t start = 0;;) {
    const std::size_t at = s.find(c, start);
    parts.push_back(s.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start));
    if (at == std::string_view::npos) return parts;
    start = at + 1;
  }
}

}  // namespace

std::string_view to_string(FaultKind k) noexcept {
  for (const auto& n : names)
    if (n.kind == k) return n.text;
  return "unknown fault";
}

std::optional<FaultKind> fault_kind_from_string(std::string_view s) noexcept {
  for (const auto& n : names)
    if (n.text == s) return n.kind;
  return std::nullopt;
}

std::optional<FaultKind> fault_kind_from_code(unsigned code) noexcept {
  if (code < 1 || code > fault_kind_count) return std::nullopt;
  return static_cast<FaultKind>(code);
}

Fault parse_fault(std::string_view text) {
  const std::size_t eq = text.find('=');
  const std::string_view kind_text = text.substr(0, eq);
  const auto kind = fault_kind_from_string(kind_text);
  if (!kind)
    fail(text, "unknown kind '" + std::string(kind_text) +
                   "' (over-current, following-error, heartbeat-loss, bus-off, sdo-abort=<index>.<sub>)");
  Fault f;
  f.kind = *kind;
  if (f.kind != FaultKind::sdo_abort) {
    if (eq != std::string_view::npos) fail(text, std::string(kind_text) + " takes no argument");
    return f;
  }
  if (eq == std::string_view::npos)
    fail(text, "sdo-abort needs its object: sdo-abort=0x6064.0[/<abort code>]");
  const std::string_view argument = text.substr(eq + 1);
  const auto code_parts = split(argument, '/');
  if (code_parts.size() > 2) fail(text, "expected <index>.<sub>[/<abort code>]");
  const auto address = split(code_parts[0], '.');
  const auto index = parse_unsigned(address[0]);
  const auto sub = address.size() == 2 ? parse_unsigned(address[1]) : std::nullopt;
  if (address.size() != 2 || !index || *index > 0xFFFF || !sub || *sub > 0xFF)
    fail(text, "the object must be <index>.<sub>, e.g. 0x6064.0");
  f.object = {static_cast<std::uint16_t>(*index), static_cast<std::uint8_t>(*sub)};
  if (code_parts.size() == 2) {
    const auto code = parse_unsigned(code_parts[1]);
    if (!code || *code == 0 || *code > 0xFFFFFFFF)
      fail(text, "the abort code must be a non-zero 32-bit number");
    f.abort = static_cast<SdoAbort>(*code);
  }
  return f;
}

ScheduledFault parse_scheduled_fault(std::string_view text) {
  // The kind's own argument may not hold ':' (it uses '.' and '/'), so ':' splits the fields.
  const auto parts = split(text, ':');
  if (parts.size() < 3 || parts.size() > 4)
    fail(text, "expected <node>:<kind>:<at seconds>[:<duration seconds>]");
  ScheduledFault s;
  const auto node = parse_unsigned(parts[0]);
  if (!node || !valid_node_id(static_cast<unsigned>(std::min<std::uint64_t>(*node, 1000))))
    fail(text, "the node must be 1..127");
  s.node = static_cast<std::uint8_t>(*node);
  s.fault = parse_fault(parts[1]);
  const auto at = parse_seconds(parts[2]);
  if (!at) fail(text, "the time must be seconds from the start (0 .. 86400)");
  s.at = *at;
  if (parts.size() == 4) {
    const auto duration = parse_seconds(parts[3]);
    if (!duration) fail(text, "the duration must be seconds (0 .. 86400)");
    if (!lasting(s.fault.kind))
      fail(text, std::string(to_string(s.fault.kind)) + " is an event: it has no duration");
    s.fault.duration = *duration;
  }
  return s;
}

std::string describe(const ScheduledFault& f) {
  std::string out = "node " + std::to_string(f.node) + ": " + std::string(to_string(f.fault.kind));
  char buf[64];
  if (f.fault.kind == FaultKind::sdo_abort) {
    std::snprintf(buf, sizeof buf, " %s (0x%08X)", to_string(f.fault.object).c_str(),
                  static_cast<unsigned>(f.fault.abort));
    out += buf;
  }
  std::snprintf(buf, sizeof buf, " at %.3f s", static_cast<double>(f.at) * 1e-9);
  out += buf;
  if (lasting(f.fault.kind)) {
    if (f.fault.duration > 0) {
      std::snprintf(buf, sizeof buf, " for %.3f s", static_cast<double>(f.fault.duration) * 1e-9);
      out += buf;
    } else {
      out += f.fault.kind == FaultKind::bus_off ? " for 1 s" : " until cleared";
    }
  }
  return out;
}

}  // namespace saw::canopen::sim
