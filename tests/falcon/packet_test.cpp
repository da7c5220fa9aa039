// The Falcon packet codec: round trips both ways, and every kind of corrupt frame refused.
#include "saw/drivers/falcon/packet.hpp"

#include <gtest/gtest.h>

#include <cstring>

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
  for (std::size_t i : {1u, 6u, 12u, 14u}) {
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
                            (i == 13 && b >= 'A' && b <= 'A' + 0x7f) ||
                            (i != 0 && i != 13 && i != 15 && b >= 'A' && b <= 'P');
      EXPECT_EQ(e == FrameError::none, in_range) << i << " " << b;
    }
}

TEST(FalconPacket, CommandStatusNibbleIsChecked) {
  Packet p = encode_command(MotorCommand{});
  p[13] = 'Q';
  MotorCommand c{};
  EXPECT_EQ(decode_command(p, c), FrameError::bad_status);
}

}  // namespace
}  // namespace saw::drivers::falcon
