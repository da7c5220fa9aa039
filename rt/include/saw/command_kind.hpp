// CommandKind: the four command kinds and two event kinds of an interface, and their signatures.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "saw/type_info.hpp"

namespace saw {

enum class CommandKind : std::uint8_t { void_command, write, read, qualified_read, void_event, write_event };

// Whether a required function or event handler must be bound for the client to start.
enum class Need : std::uint8_t { required, optional };

// The full signature of a command or event, compared at connect and printed in errors.
struct Signature {
  CommandKind kind = CommandKind::void_command;
  TypeInfo arg{};     // write: argument; read: result; qualified read: qualifier
  TypeInfo result{};  // qualified read: result

  friend bool operator==(const Signature&, const Signature&) = default;
};

// With `layout`, each type also shows its layout version and size (for mismatches of those).
inline std::string to_string(const Signature& s, bool layout = false) {
  const auto n = [layout](TypeInfo t) {
    if (!layout) return std::string(t.name);
    return std::string(t.name) + " (layout v" + std::to_string(t.version) + ", " + std::to_string(t.size) +
           " B)";
  };
  switch (s.kind) {
    case CommandKind::void_command:
      return "void command";
    case CommandKind::write:
      return "write command<" + n(s.arg) + ">";
    case CommandKind::read:
      return "read command<" + n(s.arg) + ">";
    case CommandKind::qualified_read:
      return "qualified read command<" + n(s.arg) + " -> " + n(s.result) + ">";
    case CommandKind::void_event:
      return "void event";
    case CommandKind::write_event:
      return "write event<" + n(s.arg) + ">";
  }
  return "?";
}

inline bool is_event(CommandKind k) { return k == CommandKind::void_event || k == CommandKind::write_event; }

}  // namespace saw
