// The Falcon packet codec: round trips both ways, and every kind of corrupt frame refused.
#include "saw/drivers/falcon/packet.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <sstream>
#include <string>

namespace saw::drivers::falcon {
namespace {

TEST(FalconPacket, CommandRoundTrips) {
  for (const int x : {0, 1, -1, 1447, -1447, 32767, -32768, 0x1234}) {
    const auto v = static_cast<std::int16_t>(x);
    MotorCommand c{{v, static_cast<std::int16_t>(-v / 2), static_cast<std::int16_t>(v ^ 0x5a5a)},
                   control::led_green | control::homing};
    MotorCommand back{};
    ASSERT_EQ(decode_command(encode_command(c), back), FrameError::none);
    EXPECT_EQ(back, c);
  }
}

TEST(FalconPacket, ReportRoundTrips) {
  DeviceReport r{{1447, -2000, 32767}, status::button_center | status::homed_all};
  DeviceReport back{};
  ASSERT_EQ(decode_report(encode_report(r), back), FrameError::none);
  EXPECT_EQ(back, r);
  EXPECT_TRUE(back.homed(0) && back.homed(1) && back.homed(2));
  EXPECT_EQ(back.buttons(), status::button_center);
}

TEST(FalconPacket, NullPacketIsAllA) {
  const Packet p = encode_command(MotorCommand{});
  EXPECT_EQ(std::memcmp(p.data(), "<AAAAAAAAAAAAAA>", 16), 0);
}

// Nibbles J,F,B,A are 9,5,1,0, lowest first: 0x0159 (the firmware puts the low nibble first).
TEST(FalconPacket, NibbleOrderIsLowestFirst) {
  Packet p = encode_report(DeviceReport{});
  p[1] = 'J', p[2] = 'F', p[3] = 'B', p[4] = 'A';
  DeviceReport r{};
  ASSERT_EQ(decode_report(p, r), FrameError::none);
  EXPECT_EQ(r.encoder[0], 0x0159);
}

TEST(FalconPacket, CorruptFramesAreRefusedAndLeaveTheOutputUntouched) {
  const DeviceReport sentinel{{7, 8, 9}, 3};
  const Packet good = encode_report(DeviceReport{{100, 200, 300}, 1});
  auto refused = [&](std::span<const std::uint8_t> f) {
    DeviceReport out = sentinel;
    const FrameError e = decode_report(f, out);
    EXPECT_EQ(out, sentinel);
    return e;
  };
  EXPECT_EQ(refused(std::span(good).first(15)), FrameError::short_frame);
  EXPECT_EQ(refused({}), FrameError::short_frame);
  Packet p = good;
  p[0] = '[';
  EXPECT_EQ(refused(p), FrameError::bad_start);
  p = good, p[15] = 0;
  EXPECT_EQ(refused(p), FrameError::bad_end);
  for (std::size_t i : {1u, 6u, 12u}) {
    p = good, p[i] = 'Q';
    EXPECT_EQ(refused(p), FrameError::bad_nibble) << i;
    p = good, p[i] = '@';
    EXPECT_EQ(refused(p), FrameError::bad_nibble) << i;
  }
  p = good, p[13] = 0x40;
  EXPECT_EQ(refused(p), FrameError::bad_status);
  p = good, p[13] = 0xc1;
  EXPECT_EQ(refused(p), FrameError::bad_status);
}

// Every single-byte corruption of a valid report either decodes to a valid report (a byte
// changed within its range) or is refused: nothing out of range gets through.
TEST(FalconPacket, EverySingleByteCorruptionIsCheckedOrInRange) {
  const Packet good = encode_report(DeviceReport{{-5, 5, 1000}, 0x25});
  for (std::size_t i = 0; i < packet_size; ++i)
    for (int b = 0; b < 256; ++b) {
      Packet p = good;
      p[i] = static_cast<std::uint8_t>(b);
      DeviceReport r{};
      const FrameError e = decode_report(p, r);
      const bool in_range = (i == 0 && b == '<') || (i == 15 && b == '>') ||
                            (i == 13 && b >= 'A' && b <= 'A' + 0x7f) || i == 14 ||
                            (i != 0 && i != 13 && i != 15 && b >= 'A' && b <= 'P');
      EXPECT_EQ(e == FrameError::none, in_range) << i << " " << b;
    }
}

// Host packets as the reference encodes them (tests/falcon/reference/falcon_reference.py, after
// libnifalcon's FalconFirmwareNovintSDK.cpp and its LED enum in FalconFirmware.h): green 0x2,
// blue 0x4, red 0x8, homing 0x1 in byte 13. Catches the LED bits taken from libnifalcon's stale
// header comment (red 0x2, green 0x4, blue 0x8): a fault would have shown green.
TEST(FalconPacket, LedAndHomingBitsAreLibnifalconsOnTheWire) {
  auto bytes = [](const MotorCommand& c) {
    const Packet p = encode_command(c);
    return std::string(p.begin(), p.end());
  };
  EXPECT_EQ(bytes({{}, control::led_green}), "<AAAAAAAAAAAACA>");
  EXPECT_EQ(bytes({{}, control::led_blue}), "<AAAAAAAAAAAAEA>");
  EXPECT_EQ(bytes({{}, control::led_red}), "<AAAAAAAAAAAAIA>");
  EXPECT_EQ(bytes({{}, control::homing | control::led_red}), "<AAAAAAAAAAAAJA>");
  EXPECT_EQ(bytes({{}, control::homing | control::led_green}), "<AAAAAAAAAAAADA>");
}

// libnifalcon's recorded host packets (util/translate_packet.py, via the reference's
// TRANSLATE_PACKET_VECTORS): byte 13 'E' is BLUE_LED (0x4) in libnifalcon's enum. The DAC words
// and nibble order must match byte for byte; today's blue (0x8) sends 'I'.
TEST(FalconPacket, RecordedLibnifalconPacketsEncodeByteForByte) {
  struct Vector {
    const char* hex;
    std::array<std::int16_t, 3> dac;
  };
  const Vector vectors[] = {
      {"3c 50 50 50 41 43 45 50 41 43 4d 50 41 45 41 3e", {4095, 3906, 4034}},
      {"3c 41 4d 4b 41 4d 4e 4b 41 49 45 4c 41 45 41 3e", {2752, 2780, 2888}},
      {"3c 46 4a 43 41 4c 4e 43 41 4f 50 43 41 45 41 3e", {661, 731, 766}},
      {"3c 4d 4b 45 50 4c 42 41 41 42 4b 44 41 45 41 3e", {-2900, 27, 929}},
      {"3c 50 49 42 41 42 50 44 50 50 47 45 41 45 41 3e", {399, -3087, 1135}},
      {"3c 4a 46 4e 50 42 4f 4a 41 4b 4c 49 50 45 41 3e", {-679, 2529, -1862}},
  };
  for (const Vector& v : vectors) {
    Packet expected{};
    std::stringstream ss(v.hex);
    for (auto& b : expected) {
      unsigned x = 0;
      ss >> std::hex >> x;
      b = static_cast<std::uint8_t>(x);
    }
    EXPECT_EQ(encode_command({v.dac, control::led_blue}), expected) << v.hex;
    MotorCommand back{};
    ASSERT_EQ(decode_command(expected, back), FrameError::none);
    EXPECT_EQ(back.dac, v.dac);
    EXPECT_EQ(back.control, control::led_blue);
  }
}

// Byte 14 of a report is "unknown" (libnifalcon checks only '<' and '>'): any value is taken.
// Catches the check that refused the whole report when byte 14 was outside 'A'..'P'.
TEST(FalconPacket, ReportByte14IsNotChecked) {
  // Encoders 0x0159, -1, 0; status 0x35 (arms 0 and 1 homed, buttons 0x5); byte 14 = 0x00, then 'Z'.
  Packet p{'<', 'J', 'F', 'B', 'A', 'P', 'P', 'P', 'P', 'A', 'A', 'A', 'A', 0x76, 0x00, '>'};
  DeviceReport r{};
  ASSERT_EQ(decode_report(p, r), FrameError::none);
  EXPECT_EQ(r.encoder, (std::array<std::int16_t, 3>{0x0159, -1, 0}));
  EXPECT_EQ(r.status, 0x35);
  p[14] = 'Z';
  EXPECT_EQ(decode_report(p, r), FrameError::none);
}

TEST(FalconPacket, CommandStatusNibbleIsChecked) {
  Packet p = encode_command(MotorCommand{});
  p[13] = 'Q';
  MotorCommand c{};
  EXPECT_EQ(decode_command(p, c), FrameError::bad_status);
}

}  // namespace
}  // namespace saw::drivers::falcon
