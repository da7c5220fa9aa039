// The socketcand protocol's raw-mode subset: ASCII `< ... >` elements between a client and a bus.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "saw/can/frame.hpp"

namespace saw::can::socketcand {

// What a client asked for, checked. The grammar (linux-can/socketcand doc/protocol.md, and what
// its server and python-can's client actually send):
//   < open <bus> >                      select a bus (answered < ok > or an error)
//   < rawmode >   < bcmmode >           every frame of the bus to the client, or none
//   < echo >                            answered with itself
//   < send <id> <len> <byte>... >       id: 1-3 hex digits (11-bit) or 8 (29-bit); len 0-8;
//                                       bytes: 1 or 2 hex digits each, exactly len of them
//   < sendrtr <id> <len> >              a remote request
//   < fdsend <id> <flags> <len> <byte>... >   CAN FD: flags hex (1 BRS, 2 ESI, 4 FDF), len decimal
struct Command {
  enum class Kind { open, rawmode, bcmmode, echo, send };
  Kind kind = Kind::echo;
  std::string bus;  // open
  Frame frame;      // send, sendrtr, fdsend
};

// Parses one element, brackets included. On failure, nullopt and `error` says what is wrong
// (sent back as `< error ... >`): unknown commands, BCM and ISO-TP commands this server does not
// implement, and every malformed field.
std::optional<Command> parse_command(std::string_view element, std::string& error);

// What the server sends for a frame seen at `wall_time` (ns since the epoch):
//   < frame 123 1700000000.123456 112233 >           classic (id: 3 or 8 hex digits)
//   < fdframe 123 05 1700000000.123456 1122... >      CAN FD, with its flags
//   < rtr 123 1700000000.123456 4 >                   remote request, with its length
std::string format_frame(const Frame& f, TimeNs wall_time);
// `< error <what> >`; `what` is reduced to printable characters without '<' and '>'.
std::string format_error(std::string_view what);

// Cuts a client's byte stream into elements. Whitespace between elements is skipped; anything
// else outside `< >`, a control character, or an element longer than max_element is an error,
// after which the framer resynchronises at the next '<'.
class Framer {
 public:
  static constexpr std::size_t max_element = 512;
  void feed(std::string_view bytes) { buffer_.append(bytes); }
  // The next complete element; or an error (`error` set, nullopt); or nullopt with `error`
  // empty when more bytes are needed.
  std::optional<std::string> next(std::string& error);

 private:
  std::string buffer_;
  bool discarding_ = false;  // inside an over-long element: dropped up to its '>'
};

}  // namespace saw::can::socketcand
