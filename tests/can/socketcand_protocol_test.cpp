// The socketcand elements saw-socketcand reads and writes, against the forms socketcand and
// python-can use (linux-can/socketcand doc/protocol.md and its raw-mode server; python-can 4.6's
// socketcand interface).
#include <gtest/gtest.h>

#include <random>

#include "saw/can/socketcand.hpp"

namespace {

using namespace saw::can;
using socketcand::Command;

std::optional<Command> ok(const std::string& element) {
  std::string error;
  auto c = socketcand::parse_command(element, error);
  EXPECT_TRUE(c.has_value()) << element << ": " << error;
  return c;
}

std::string refused(const std::string& element) {
  std::string error;
  EXPECT_FALSE(socketcand::parse_command(element, error).has_value()) << element << " was accepted";
  return error;
}

TEST(SocketcandProtocol, TheHandshakeCommands) {
  EXPECT_EQ(ok("< open vcan0 >")->bus, "vcan0");
  EXPECT_EQ(ok("<open can0>")->bus, "can0");  // the protocol document writes it without spaces too
  EXPECT_EQ(ok("< rawmode >")->kind, Command::Kind::rawmode);
  EXPECT_EQ(ok("< bcmmode >")->kind, Command::Kind::bcmmode);
  EXPECT_EQ(ok("< echo >")->kind, Command::Kind::echo);
}

TEST(SocketcandProtocol, SendAsPythonCanAndSocketcandWriteIt) {
  // python-can: f"< send {id:03X} {dlc:X} {' '.join(f'{x:x}' for x in data)} >"
  auto c = ok("< send 123 3 11 2 ff >");
  EXPECT_EQ(c->kind, Command::Kind::send);
  EXPECT_EQ(c->frame.id, 0x123u);
  ASSERT_EQ(c->frame.len, 3);
  EXPECT_EQ(c->frame.data[0], 0x11);
  EXPECT_EQ(c->frame.data[1], 0x02);
  EXPECT_EQ(c->frame.data[2], 0xFF);
  c = ok("< send 1AAAAAAA 2 1 F1 >");  // the protocol document's example
  EXPECT_TRUE(c->frame.extended());
  EXPECT_EQ(c->frame.can_id(), 0x1AAAAAAAu);
  EXPECT_EQ(c->frame.len, 2);
  c = ok("< send 00000001 0 >");  // 8 digits make it extended, whatever its value
  EXPECT_TRUE(c->frame.extended());
  c = ok("< send 123 0 >");
  EXPECT_EQ(c->frame.len, 0);
  c = ok("< sendrtr 7FF 4 >");
  EXPECT_TRUE(c->frame.remote());
  EXPECT_EQ(c->frame.len, 4);
  c = ok("< fdsend 123 1 12 0 1 2 3 4 5 6 7 8 9 a b >");
  EXPECT_TRUE(c->frame.fd());
  EXPECT_EQ(c->frame.flags, CANFD_FDF | CANFD_BRS);
  EXPECT_EQ(c->frame.len, 12);
  EXPECT_EQ(c->frame.data[11], 0x0B);
  for (const auto& e : {"< send 123 3 11 2 ff >", "< send 1AAAAAAA 2 1 F1 >", "< sendrtr 7FF 4 >"})
    EXPECT_TRUE(well_formed(ok(e)->frame)) << e;
}

TEST(SocketcandProtocol, EveryMalformedFieldIsRefusedWithTheReason) {
  EXPECT_NE(refused("< >").find("empty"), std::string::npos);
  EXPECT_NE(refused("open vcan0").find("'< command"), std::string::npos);
  EXPECT_NE(refused("< open >").find("takes 1 argument"), std::string::npos);
  EXPECT_NE(refused("< rawmode now >").find("takes 0 arguments"), std::string::npos);
  EXPECT_NE(refused("< send 800 0 >").find("up to 7FF"), std::string::npos);
  EXPECT_NE(refused("< send 1234 0 >").find("identifier"), std::string::npos);
  EXPECT_NE(refused("< send 3FFFFFFF 0 >").find("up to 1FFFFFFF"), std::string::npos);
  EXPECT_NE(refused("< send xyz 0 >").find("identifier"), std::string::npos);
  EXPECT_NE(refused("< send 123 9 1 2 3 4 5 6 7 8 9 >").find("0 to 8"), std::string::npos);
  EXPECT_NE(refused("< send 123 2 11 >").find("length 2 but 1 data bytes"), std::string::npos);
  EXPECT_NE(refused("< send 123 1 100 >").find("1 or 2 hex digits"), std::string::npos);
  EXPECT_NE(refused("< send 123 1 g >").find("1 or 2 hex digits"), std::string::npos);
  EXPECT_NE(refused("< send 123 >").find("takes an identifier"), std::string::npos);
  EXPECT_NE(refused("< send 123 -1 >").find("0 to 8"), std::string::npos);
  EXPECT_NE(refused("< sendrtr 123 2 11 >").find("takes 2 arguments"), std::string::npos);
  EXPECT_NE(refused("< fdsend 123 8 1 0 >").find("flags"), std::string::npos);
  EXPECT_NE(refused("< fdsend 123 1 13 >").find("12, 16"), std::string::npos);
  EXPECT_NE(refused("< add 1 0 123 1 11 >").find("not supported"), std::string::npos);
  EXPECT_NE(refused("< isotpmode >").find("not supported"), std::string::npos);
  EXPECT_NE(refused("< frobnicate >").find("unknown command 'frobnicate'"), std::string::npos);
}

TEST(SocketcandProtocol, FramesAsSocketcandSendsThemAndPythonCanReadsThem) {
  const std::uint8_t bytes[] = {0x11, 0x22, 0x33, 0x44};
  EXPECT_EQ(socketcand::format_frame(classic(0x123, bytes), 23'424'242'000),
            "< frame 123 23.424242 11223344 >");
  Frame ext = classic(0, bytes);
  ext.id = 0x1AAAAAAA | CAN_EFF_FLAG;
  EXPECT_EQ(socketcand::format_frame(ext, 1'000'000'000), "< frame 1AAAAAAA 1.000000 11223344 >");
  EXPECT_EQ(socketcand::format_frame(classic(0x7, {}), 0), "< frame 007 0.000000  >");
  Frame rtr;
  rtr.id = 0x123 | CAN_RTR_FLAG;
  rtr.len = 4;
  EXPECT_EQ(socketcand::format_frame(rtr, 23'424'242'000), "< rtr 123 23.424242 4 >");
  Frame fd = classic(0x123, bytes);
  fd.flags = CANFD_FDF | CANFD_BRS;
  EXPECT_EQ(socketcand::format_frame(fd, 1'500'000'000), "< fdframe 123 05 1.500000 11223344 >");
  EXPECT_EQ(socketcand::format_error("bad <x> \x01 thing"), "< error bad x  thing >");
}

TEST(SocketcandProtocol, TheFramerCutsElementsAndResynchronisesAfterGarbage) {
  socketcand::Framer f;
  std::string error;
  f.feed("< open vcan0 >< raw");
  EXPECT_EQ(f.next(error).value_or(""), "< open vcan0 >");
  EXPECT_FALSE(f.next(error).has_value());
  EXPECT_TRUE(error.empty()) << "half an element: wait for more";
  f.feed("mode >\n  junk < echo >");
  EXPECT_EQ(f.next(error).value_or(""), "< rawmode >");
  EXPECT_FALSE(f.next(error).has_value());
  EXPECT_NE(error.find("outside"), std::string::npos);
  EXPECT_EQ(f.next(error).value_or(""), "< echo >");
  f.feed("< send <echo >");
  EXPECT_FALSE(f.next(error).has_value());
  EXPECT_NE(error.find("'<' inside"), std::string::npos);
  EXPECT_EQ(f.next(error).value_or(""), "<echo >");
  f.feed(std::string("< a\x01 >< echo >"));
  EXPECT_FALSE(f.next(error).has_value());
  EXPECT_NE(error.find("control character"), std::string::npos);
  EXPECT_EQ(f.next(error).value_or(""), "< echo >");
  f.feed("< " + std::string(600, 'x'));
  EXPECT_FALSE(f.next(error).has_value());
  EXPECT_NE(error.find("longer than"), std::string::npos);
  f.feed(std::string(100, 'y') + " >< echo >");  // the rest of the long one is dropped silently
  EXPECT_EQ(f.next(error).value_or(""), "< echo >");
  EXPECT_TRUE(error.empty());
  f.feed("<" + std::string(2000, 'z') + ">< echo >");  // all in one read
  EXPECT_FALSE(f.next(error).has_value());
  EXPECT_NE(error.find("longer than"), std::string::npos);
  EXPECT_EQ(f.next(error).value_or(""), "< echo >");
}

// What a hostile or broken client can send: random tokens, brackets and bytes in random chunks.
// Nothing crashes, every element the framer yields is bounded, and every frame a command carries
// is one the bus would accept.
TEST(SocketcandProtocol, RandomInputNeverCrashesAndOnlyWellFormedFramesComeOut) {
  const std::vector<std::string> tokens = {
      "<",   ">",   " ",        "send",     "fdsend", "sendrtr", "open", "rawmode", "echo", "123",
      "7FF", "800", "1AAAAAAA", "3FFFFFFF", "0",      "8",       "12",   "64",      "9",    "11",
      "ff",  "F",   "zz",       "-1",       "\x01",   "\n",      "\t",   "\xff",    "add",  "vcan0"};
  std::mt19937 rng(1234);
  socketcand::Framer framer;
  std::size_t elements = 0, commands = 0, frames = 0;
  for (int round = 0; round < 20000; ++round) {
    std::string chunk;
    if (round % 4 == 0) {  // a command's shape with random fields, often almost right
      static const char* kinds[] = {"send", "sendrtr", "fdsend"};
      static const char* ids[] = {"123", "7FF", "800", "1AAAAAAA", "3FFFFFFF", "zz", "1"};
      const std::string kind = kinds[rng() % 3];
      chunk = "< " + kind + " " + ids[rng() % 7] + " ";
      if (kind == "fdsend") chunk += std::to_string(rng() % 9) + " ";
      const auto len =
          static_cast<unsigned>(kind == "fdsend" ? (rng() % 2 != 0 ? 12 : rng() % 70) : rng() % 10);
      chunk += std::to_string(len);
      const unsigned bytes = len + (rng() % 4 == 0 ? 1 : 0);
      for (unsigned i = 0; i < bytes; ++i) chunk += " " + std::to_string(rng() % 100);
      chunk += " >";
    }
    const int n = static_cast<int>(rng() % 24);
    for (int i = 0; i < n; ++i) {
      if (rng() % 8 == 0)
        chunk += static_cast<char>(rng() % 256);
      else
        chunk += tokens[rng() % tokens.size()] + (rng() % 2 != 0 ? " " : "");
    }
    framer.feed(chunk);
    std::string error;
    for (int guard = 0; guard < 1000; ++guard) {
      const auto element = framer.next(error);
      if (!element && error.empty()) break;
      if (!element) continue;
      ++elements;
      ASSERT_LE(element->size(), socketcand::Framer::max_element);
      std::string why;
      const auto c = socketcand::parse_command(*element, why);
      if (!c) {
        EXPECT_FALSE(why.empty());
        continue;
      }
      ++commands;
      if (c->kind == Command::Kind::send) {
        ++frames;
        EXPECT_TRUE(well_formed(c->frame)) << *element;
      }
    }
  }
  EXPECT_GT(elements, 5000u);
  EXPECT_GT(commands, 10u) << "the generator never made a valid command: the test proves little";
  EXPECT_GT(frames, 0u);
}

}  // namespace
