// FaultInfo: why a component (a task, a device driver) went to FAULT, in terms any of them can use.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <tuple>

#include "saw/clock.hpp"
#include "saw/status.hpp"

namespace saw {

// Which check failed.
enum class FaultCode : std::uint8_t {
  none,
  input_missing,      // an input never arrived within its start-up grace
  input_stale,        // no fresh input for longer than allowed
  input_not_finite,   // inputs kept coming, but not finite, for longer than allowed
  output_not_finite,  // a command computed to send (a force) was not finite: not sent
  device_error,       // the device reported an error (a CANopen emergency): `detail` is its code
  device_lost,        // the device stopped answering (a missed CANopen heartbeat, a USB unplug)
  limit_exceeded,     // a measured value left its safe range (a joint limit, a current)
  device_fault,       // a device this one drives reports FAULT (its own fault says why)
  device_disabled,    // a device this one drives stayed disabled: it cannot be driven
  config_mismatch,    // a peer's configuration no longer matches this one's (a wave port's impedance)
  deadline_missed,    // the task missed more periods than its deadline policy allows: `detail` periods
};
constexpr std::size_t enum_count(FaultCode) { return 12; }
constexpr std::string_view enum_type_name(FaultCode) { return "saw::FaultCode"; }

constexpr std::string_view to_string(FaultCode c) {
  switch (c) {
    case FaultCode::none:
      return "none";
    case FaultCode::input_missing:
      return "input missing";
    case FaultCode::input_stale:
      return "input stale";
    case FaultCode::input_not_finite:
      return "input not finite";
    case FaultCode::output_not_finite:
      return "output not finite";
    case FaultCode::device_error:
      return "device error";
    case FaultCode::device_lost:
      return "device lost";
    case FaultCode::limit_exceeded:
      return "limit exceeded";
    case FaultCode::device_fault:
      return "device in FAULT";
    case FaultCode::device_disabled:
      return "device not enabled";
    case FaultCode::config_mismatch:
      return "configuration mismatch";
    case FaultCode::deadline_missed:
      return "deadline missed";
  }
  return "?";
}

// A state-table column and an event of whoever faults: everything a user or a GUI needs to say
// why. Times are the reporter's clock (CLOCK_MONOTONIC, or the stepped clock). Plain and
// bounded: filled in RT code without allocating.
struct FaultInfo {
  static constexpr std::string_view type_name = "saw::FaultInfo";
  // 2: FaultCode::device_fault; 3: device_disabled; 4: config_mismatch; 5: deadline_missed
  static constexpr std::uint32_t layout_version = 5;
  static constexpr std::size_t max_source = 23;  // characters, then at least one NUL

  FaultCode code = FaultCode::none;
  Status last_read = Status::ok;  // the input's last read result (disconnected: its peer is gone)
  std::uint32_t detail = 0;   // the device's own code (CANopen error code, USB error), periods missed, or 0
  TimeNs age_ns = 0;          // how old the last good input was (stale, not finite); how late the wake-up
  TimeNs time = 0;            // when the fault was raised
  TimeNs since_start_ns = 0;  // the same, from the reporter's first cycle
  // Which input, side or device the check was about ("master", "node 5", "usb 1-2"); "" if none.
  std::array<char, max_source + 1> source{};

  static constexpr auto fields =
      std::tuple{&FaultInfo::code, &FaultInfo::last_read,      &FaultInfo::detail, &FaultInfo::age_ns,
                 &FaultInfo::time, &FaultInfo::since_start_ns, &FaultInfo::source};
  static constexpr bool valid(const FaultInfo& f) noexcept { return f.source[max_source] == '\0'; }

  constexpr std::string_view source_name() const noexcept {
    std::size_t n = 0;
    while (n < max_source && source[n] != '\0') ++n;
    return {source.data(), n};
  }
  // Truncated to max_source characters: a label for people, not a key.
  constexpr void set_source(std::string_view s) noexcept {
    source = {};
    for (std::size_t i = 0; i < s.size() && i < max_source; ++i) source[i] = s[i];
  }
};
// Crosses processes byte for byte (the gateway publishes it): a layout change bumps its version.
static_assert(sizeof(FaultInfo) == 56 && offsetof(FaultInfo, last_read) == 1 &&
              offsetof(FaultInfo, detail) == 4 && offsetof(FaultInfo, age_ns) == 8 &&
              offsetof(FaultInfo, time) == 16 && offsetof(FaultInfo, since_start_ns) == 24 &&
              offsetof(FaultInfo, source) == 32);

// One line for people: "master input stale: 23.4 ms old (last read: disconnected), at t=4.512 s",
// "deadline missed: 12 periods in a row (last wake-up 11.8 ms late), at t=2.031 s".
// Not for RT code (it allocates).
inline std::string to_string(const FaultInfo& f) {
  if (f.code == FaultCode::none) return "no fault";
  if (f.code == FaultCode::deadline_missed) {
    char b[160];
    std::snprintf(b, sizeof b, "deadline missed: %u periods %s (last wake-up %.1f ms late), at t=%.3f s",
                  static_cast<unsigned>(f.detail), f.source_name().empty() ? "" : f.source.data(),
                  static_cast<double>(f.age_ns) * 1e-6, static_cast<double>(f.since_start_ns) * 1e-9);
    return b;
  }
  std::string s(f.source_name());
  if (!s.empty()) s += ' ';
  s += to_string(f.code);
  char b[128];
  if (f.code == FaultCode::input_stale || f.code == FaultCode::input_not_finite) {
    std::snprintf(b, sizeof b, ": %.1f ms old", static_cast<double>(f.age_ns) * 1e-6);
    s += b;
  }
  if (f.detail != 0) {
    std::snprintf(b, sizeof b, " (code 0x%04x)", static_cast<unsigned>(f.detail));
    s += b;
  }
  if (f.last_read != Status::ok) s += " (last read: " + std::string(to_string(f.last_read)) + ")";
  std::snprintf(b, sizeof b, ", at t=%.3f s", static_cast<double>(f.since_start_ns) * 1e-9);
  return s + b;
}

}  // namespace saw
