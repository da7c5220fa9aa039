// Bindings: where connect() sends a function's calls and an event's deliveries (internal).
#pragma once

#include <cstdint>
#include <functional>

#include "saw/detail/invoker.hpp"
#include "saw/state_table.hpp"
#include "saw/status.hpp"

namespace saw {
struct Command;
}

namespace saw::detail {

class Mailbox;

// A proxy's void/write command (the server is in another process): hands the argument on at
// once, in the caller's thread, and says whether it was taken.
using ForwardCall = std::function<Status(const void* arg)>;
// A proxy's read command: the value with the time of the row it came from.
using StampedRead = std::function<Status(void* out, RowStamp& stamp)>;

// What connect() fills in for a function. Set before start, read-only while running.
struct FunctionBinding {
  Mailbox* mailbox = nullptr;  // queued void/write: the server's mailbox for this connection
  std::uint32_t target = 0;
  Invoker direct{};                      // void/write to a server without a thread: run now
  const ForwardCall* forward = nullptr;  // void/write to a proxy: hand on now, with its status
  const Command* command = nullptr;      // read, qualified read
  const StampedRead* stamped = nullptr;  // read from a proxy: with the time of its row
  bool check_values = false;             // the server is in another process: results are checked
};

// One observer of an event: a mailbox slot in the observer's thread, or a direct call when
// the observer has no thread of its own.
struct Observer {
  Mailbox* mailbox = nullptr;
  std::uint32_t target = 0;
  Invoker direct{};
};

}  // namespace saw::detail
