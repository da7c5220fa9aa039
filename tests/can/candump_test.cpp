// candump -L lines and cansend frames: written, parsed back, and rejected when malformed.
#include "saw/can/candump.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "saw/testing/unique_name.hpp"

namespace {

using namespace saw::can;

Frame parsed(const std::string& text) {
  std::string error;
  const auto f = parse_frame(text, &error);
  EXPECT_TRUE(f.has_value()) << text << ": " << error;
  return f.value_or(Frame{});
}

std::string refused(const std::string& text) {
  std::string error;
  const auto f = parse_frame(text, &error);
  EXPECT_FALSE(f.has_value()) << text << " was accepted";
  return error;
}

TEST(Candump, ALogLineAsCandumpWritesIt) {
  const std::uint8_t bytes[] = {0x11, 0x22, 0x33};
  EXPECT_EQ(format_log_line(1'700'000'000'123'456'789, "vcan0", classic(0x123, bytes)),
            "(1700000000.123456) vcan0 123#112233");
  EXPECT_EQ(format_log_line(5'000'001'000, "can1", Frame{}), "(0000000005.000001) can1 000#");
}

TEST(Candump, ExtendedIdsRemoteRequestsFdAndErrorFramesRoundTrip) {
  const char* lines[] = {
      "(1700000000.123456) vcan0 123#112233",
      "(1700000000.000001) vcan0 1ABCDEF0#DEADBEEF",
      "(1700000000.000002) vcan0 00000001#",
      "(1700000000.000003) vcan0 123#R",
      "(1700000000.000004) vcan0 7FF#R8",
      "(1700000000.000005) can0 123##1AABBCCDDEEFF0011",
      "(1700000000.000006) can0 1FFFFFFF##300112233445566778899AABBCCDDEEFF00112233445566778899AABBCCDDEEFF"
      "00112233445566778899AABBCCDDEEFF00112233445566778899AABBCCDDEEFF",
      "(1700000000.000007) can0 20000004#0004000000000000",
      "(1700000000.000008) can0 123#1122334455667788_E",
  };
  for (const std::string line : lines) {
    std::string error;
    const auto e = parse_log_line(line, &error);
    ASSERT_TRUE(e.has_value()) << line << ": " << error;
    EXPECT_EQ(format_log_line(e->time, e->interface, e->frame), line);
  }
  const auto ext = parse_log_line(lines[1]);
  EXPECT_TRUE(ext->frame.extended());
  EXPECT_EQ(ext->frame.can_id(), 0x1ABCDEF0u);
  EXPECT_EQ(ext->frame.len, 4);
  EXPECT_EQ(ext->time, 1'700'000'000'000'001'000);
  EXPECT_EQ(ext->interface, "vcan0");
  const auto rtr = parse_frame("7FF#R8");
  EXPECT_TRUE(rtr->remote());
  EXPECT_EQ(rtr->len, 8);
  const auto fd = parse_log_line(lines[5]);
  EXPECT_TRUE(fd->frame.fd());
  EXPECT_EQ(fd->frame.flags, CANFD_FDF | CANFD_BRS);
  EXPECT_EQ(fd->frame.len, 8);
  EXPECT_TRUE(well_formed(fd->frame));
  const auto fd64 = parse_log_line(lines[6]);
  EXPECT_EQ(fd64->frame.len, 64);
  EXPECT_EQ(fd64->frame.flags, CANFD_FDF | CANFD_BRS | CANFD_ESI);
  const auto err = parse_log_line(lines[7]);
  EXPECT_TRUE(err->frame.error());
  EXPECT_FALSE(err->frame.extended());
  EXPECT_EQ(parse_frame("123#1122334455667788_E")->reserved1, 0xE);
}

TEST(Candump, ParsingAcceptsCansendsDotsLowerCaseAndLineEnds) {
  EXPECT_EQ(format_frame(parsed("1ab#11.22.33")), "1AB#112233");
  EXPECT_EQ(format_frame(parsed("123##0")), "123##0");
  EXPECT_TRUE(parse_log_line("(1.000000) can0 123#11\r\n").has_value());
}

TEST(Candump, MalformedFramesAreRefusedWithTheReason) {
  EXPECT_NE(refused("123").find("no '#'"), std::string::npos);
  EXPECT_NE(refused("12#11").find("3 hex digits"), std::string::npos);
  EXPECT_NE(refused("800#11").find("above 7FF"), std::string::npos);
  EXPECT_NE(refused("40000000#").find("above 1FFFFFFF"), std::string::npos);
  EXPECT_NE(refused("E0000000#").find("bits above 3FFFFFFF"), std::string::npos);
  EXPECT_NE(refused("12G#").find("not hexadecimal"), std::string::npos);
  EXPECT_NE(refused("123#112").find("whole hex bytes"), std::string::npos);
  EXPECT_NE(refused("123#112233445566778899").find("more than 8"), std::string::npos);
  EXPECT_NE(refused("123##1" + std::string(130, 'A')).find("more than 64"), std::string::npos);
  EXPECT_NE(refused("123##1112233445566778899AABBCCDD").find("not 13"), std::string::npos);
  EXPECT_NE(refused("123##").find("flags digit"), std::string::npos);
  EXPECT_NE(refused("123##8AA").find("flags digit"), std::string::npos);
  EXPECT_NE(refused("123#R9").find("0 to 8"), std::string::npos);
  EXPECT_NE(refused("123#1122_E").find("raw DLC"), std::string::npos);
  EXPECT_NE(refused("20000004##0").find("error frame"), std::string::npos);
}

TEST(Candump, MalformedLogLinesAreRefusedWithTheReason) {
  std::string error;
  EXPECT_FALSE(parse_log_line("1700000000.123456 vcan0 123#11", &error));
  EXPECT_NE(error.find("starts with"), std::string::npos);
  EXPECT_FALSE(parse_log_line("(1700000000.1234) vcan0 123#11", &error));
  EXPECT_NE(error.find("6 digits"), std::string::npos);
  EXPECT_FALSE(parse_log_line("(17000x0000.123456) vcan0 123#11", &error));
  EXPECT_NE(error.find("not decimal"), std::string::npos);
  EXPECT_FALSE(parse_log_line("(1700000000.123456) vcan0", &error));
  EXPECT_NE(error.find("interface frame"), std::string::npos);
  EXPECT_FALSE(parse_log_line("(1700000000.123456) vcan0 123#1", &error));
  EXPECT_NE(error.find("whole hex bytes"), std::string::npos);
}

TEST(Candump, TheWriterStampsWallClockTimeAndEveryLineParsesBack) {
  const std::string path = "/tmp/" + saw::testing::unique_name("saw-candump-test-") + ".log";
  const std::uint8_t bytes[] = {1, 2};
  const saw::TimeNs wall_before = saw::monotonic_now() + wall_clock_offset();
  {
    CandumpWriter log(path, "vcan0");
    log.write(Received{classic(0x42, bytes), saw::monotonic_now()});
    Frame fd = classic(0x43, bytes);
    fd.flags = CANFD_FDF;
    log.write(Received{fd, saw::monotonic_now()}, "other");
  }
  std::ifstream in(path);
  std::string line;
  std::vector<LogEntry> entries;
  while (std::getline(in, line)) {
    const auto e = parse_log_line(line);
    ASSERT_TRUE(e.has_value()) << line;
    entries.push_back(*e);
  }
  std::remove(path.c_str());
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].interface, "vcan0");
  EXPECT_EQ(format_frame(entries[0].frame), "042#0102");
  EXPECT_EQ(entries[1].interface, "other");
  EXPECT_EQ(format_frame(entries[1].frame), "043##00102");
  EXPECT_GE(entries[0].time, wall_before - 1'000'000);  // microsecond resolution, a clock apart
  EXPECT_LE(entries[0].time, wall_before + 5'000'000'000);
  EXPECT_THROW(CandumpWriter("/nonexistent-dir/x.log"), std::runtime_error);
}

}  // namespace
