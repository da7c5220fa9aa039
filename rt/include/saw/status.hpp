// Status: the result of every call that crosses a component boundary at run time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace saw {

enum class Status : std::uint8_t {
  ok,
  queue_full,    // the mailbox had no free slot; nothing was queued
  disconnected,  // the function is not bound, or its server is gone
  no_data,       // the state table has no row (yet) for what was asked
  overwritten,   // the row asked for has left the state-table ring
  busy,          // a consistent read could not be had after many tries
  timeout,       // a non-RT caller waited longer than allowed
  invalid,       // the argument was rejected (NaN, out of range, wrong size)
};
constexpr std::size_t enum_count(Status) { return 8; }  // a status read from another process is checked

constexpr std::string_view to_string(Status s) {
  switch (s) {
    case Status::ok:
      return "ok";
    case Status::queue_full:
      return "queue_full";
    case Status::disconnected:
      return "disconnected";
    case Status::no_data:
      return "no_data";
    case Status::overwritten:
      return "overwritten";
    case Status::busy:
      return "busy";
    case Status::timeout:
      return "timeout";
    case Status::invalid:
      return "invalid";
  }
  return "unknown";
}

}  // namespace saw
