// PDO mappings: checks, the configuration sequence, and packing values into frames and back.
#include "saw/canopen/pdo.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "saw/canopen/sync.hpp"

namespace {

using namespace saw::canopen;
using saw::can::Frame;

constexpr std::uint8_t node = 3;

PdoMapping rpdo1() {
  PdoMapping m;
  m.kind = PdoKind::rpdo;
  m.number = 1;
  m.cob_id = default_pdo_cob_id(PdoKind::rpdo, 1, node);
  m.map({0x6040, 0}, DataType::unsigned16)
      .map({0x607A, 0}, DataType::integer32)
      .map({0x6060, 0}, DataType::integer8);
  return m;
}

PdoMapping tpdo1() {
  PdoMapping m;
  m.kind = PdoKind::tpdo;
  m.number = 1;
  m.cob_id = default_pdo_cob_id(PdoKind::tpdo, 1, node);
  m.map({0x6041, 0}, DataType::unsigned16)
      .map({0x6064, 0}, DataType::integer32)
      .map({0x6077, 0}, DataType::integer16);
  return m;
}

TEST(CanopenPdo, DefaultIdentifiersFollowThePredefinedConnectionSet) {
  EXPECT_EQ(default_pdo_cob_id(PdoKind::tpdo, 1, node), 0x183u);
  EXPECT_EQ(default_pdo_cob_id(PdoKind::rpdo, 1, node), 0x203u);
  EXPECT_EQ(default_pdo_cob_id(PdoKind::tpdo, 2, node), 0x283u);
  EXPECT_EQ(default_pdo_cob_id(PdoKind::rpdo, 4, node), 0x503u);
  EXPECT_EQ(default_pdo_cob_id(PdoKind::rpdo, 5, node), pdo_invalid);
  EXPECT_EQ(rpdo1().communication_index(), 0x1400);
  EXPECT_EQ(rpdo1().mapping_index(), 0x1600);
  EXPECT_EQ(tpdo1().communication_index(), 0x1800);
  EXPECT_EQ(tpdo1().mapping_index(), 0x1A00);
}

TEST(CanopenPdo, EntriesEncodeAsCiA301Writes) {
  const PdoEntry e = PdoEntry::of({0x607A, 0}, DataType::integer32);
  EXPECT_EQ(e.to_u32(), 0x607A0020u);
  const PdoEntry back = PdoEntry::from_u32(0x60410010);
  EXPECT_EQ(back.address, (ObjectAddress{0x6041, 0}));
  EXPECT_EQ(back.bits, 16);
  EXPECT_EQ(back.type, DataType::unsigned16);
  const PdoEntry dummy = PdoEntry::from_u32(0x00020008);
  EXPECT_TRUE(dummy.dummy());
  EXPECT_EQ(dummy.type, DataType::integer8);
}

TEST(CanopenPdo, ConfigurationIsTheCiA301Sequence) {
  PdoMapping m = tpdo1();
  m.event_timer = 10;
  m.inhibit_time = 5;
  const auto w = configuration_writes(m);
  ASSERT_EQ(w.size(), 10u);
  EXPECT_EQ(w[0].address, (ObjectAddress{0x1800, 1}));
  EXPECT_EQ(w[0].value, 0x80000183u) << "disabled first";
  EXPECT_EQ(w[1].address, (ObjectAddress{0x1A00, 0}));
  EXPECT_EQ(w[1].value, 0u) << "then the count cleared";
  EXPECT_EQ(w[1].type, DataType::unsigned8);
  EXPECT_EQ(w[2].address, (ObjectAddress{0x1A00, 1}));
  EXPECT_EQ(w[2].value, 0x60410010u);
  EXPECT_EQ(w[3].value, 0x60640020u);
  EXPECT_EQ(w[4].value, 0x60770010u);
  EXPECT_EQ(w[5].address, (ObjectAddress{0x1A00, 0}));
  EXPECT_EQ(w[5].value, 3u);
  EXPECT_EQ(w[6].address, (ObjectAddress{0x1800, 2}));
  EXPECT_EQ(w[6].value, 1u) << "SYNC";
  EXPECT_EQ(w[7].address, (ObjectAddress{0x1800, 3}));
  EXPECT_EQ(w[7].type, DataType::unsigned16);
  EXPECT_EQ(w[8].address, (ObjectAddress{0x1800, 5}));
  EXPECT_EQ(w[9].address, (ObjectAddress{0x1800, 1}));
  EXPECT_EQ(w[9].value, 0x183u) << "enabled last";

  PdoMapping off;
  off.kind = PdoKind::rpdo;
  off.number = 3;
  off.enabled = false;
  const auto d = configuration_writes(off);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].address, (ObjectAddress{0x1402, 1}));
  EXPECT_EQ(d[0].value, 0x80000000u);
}

TEST(CanopenPdo, CheckRefusesWhatADeviceWould) {
  const auto refused = [](const PdoMapping& m, const std::string& fragment) {
    try {
      check(m);
      ADD_FAILURE() << "accepted; expected: " << fragment;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  PdoMapping m = rpdo1();
  m.map({0x60FF, 0}, DataType::integer32);
  refused(m, "88 bits mapped, a classic PDO holds 64");
  m = rpdo1();
  m.cob_id = 0x605;
  refused(m, "reserved");
  m.cob_id = 0x080;
  refused(m, "reserved");
  m.cob_id = 0x800;
  refused(m, "11-bit");
  m = rpdo1();
  m.number = 0;
  refused(m, "1..512");
  m = rpdo1();
  m.entries[1].bits = 16;
  refused(m, "entry 2 (0x607A:00): 16 bits mapped, INTEGER32 has 32");
  m = rpdo1();
  m.entries[0].type = DataType::visible_string;
  refused(m, "cannot be mapped");
  PdoMapping empty = rpdo1();
  empty.count = 0;
  refused(empty, "no entry");
  PdoMapping full;
  for (int i = 0; i < 8; ++i) full.map({0x2000, static_cast<std::uint8_t>(i + 1)}, DataType::unsigned8);
  EXPECT_THROW(full.map({0x2000, 9}, DataType::unsigned8), std::invalid_argument);
}

TEST(CanopenPdo, PacksValuesLittleEndianInMappingOrder) {
  PdoPacker p(rpdo1());
  EXPECT_EQ(p.frame().id, 0x203u);
  EXPECT_EQ(p.frame().len, 7);
  ASSERT_EQ(p.set(0, 0x000F), Codec::ok);
  ASSERT_EQ(p.set(1, -2), Codec::ok);
  ASSERT_EQ(p.set(2, 8), Codec::ok);
  const std::vector<std::uint8_t> expected{0x0F, 0x00, 0xFE, 0xFF, 0xFF, 0xFF, 0x08};
  EXPECT_EQ(std::vector<std::uint8_t>(p.frame().data, p.frame().data + 7), expected);
  EXPECT_EQ(p.set(0, 70000), Codec::too_high);
  EXPECT_EQ(p.set(2, -129), Codec::too_low);
  EXPECT_EQ(p.set(1, 0.5), Codec::invalid);
  EXPECT_EQ(p.set(3, 1), Codec::invalid) << "no such slot";
  EXPECT_EQ(std::vector<std::uint8_t>(p.frame().data, p.frame().data + 7), expected)
      << "refused values change nothing";
}

TEST(CanopenPdo, UnpacksWhatWasPacked) {
  PdoMapping m = tpdo1();
  PdoPacker drive(m);
  PdoUnpacker master(m);
  ASSERT_EQ(drive.set(0, 0x1237), Codec::ok);
  ASSERT_EQ(drive.set(1, -123456), Codec::ok);
  ASSERT_EQ(drive.set(2, -250), Codec::ok);
  EXPECT_FALSE(master.has_data());
  std::uint16_t status = 0;
  EXPECT_EQ(master.get(0, status), Codec::invalid) << "nothing received yet";
  ASSERT_EQ(master.receive(drive.frame()), PdoReceive::ok);
  std::int32_t position = 0;
  std::int16_t torque = 0;
  ASSERT_EQ(master.get(0, status), Codec::ok);
  ASSERT_EQ(master.get(1, position), Codec::ok);
  ASSERT_EQ(master.get(2, torque), Codec::ok);
  EXPECT_EQ(status, 0x1237);
  EXPECT_EQ(position, -123456);
  EXPECT_EQ(torque, -250);
  std::uint8_t small = 0;
  EXPECT_EQ(master.get(1, small), Codec::too_low) << "the target type must hold the value";
}

TEST(CanopenPdo, BitGranularEntriesAndDummies) {
  PdoMapping m;
  m.kind = PdoKind::rpdo;
  m.cob_id = 0x300 + node;
  m.map(PdoEntry{{0x2000, 1}, 1, DataType::boolean})
      .map(PdoEntry{{0x2000, 2}, 1, DataType::boolean})
      .map(PdoEntry::from_u32(0x00050006))  // 6 bits of dummy... of UNSIGNED8: refused by check
      .map({0x2001, 0}, DataType::unsigned8);
  EXPECT_THROW(check(m), std::invalid_argument);
  m.entries[2] = PdoEntry::from_u32(0x00050008);  // a whole UNSIGNED8 dummy
  PdoPacker p(m);
  EXPECT_EQ(p.frame().len, 3);  // 1 + 1 + 8 + 8 bits
  ASSERT_EQ(p.set(0, true), Codec::ok);
  ASSERT_EQ(p.set(1, false), Codec::ok);
  ASSERT_EQ(p.set(3, 0xAB), Codec::ok);
  EXPECT_EQ(p.frame().data[0], 0x01);
  EXPECT_EQ(p.frame().data[1], 0xAC);  // 0xAB << 2, low byte
  EXPECT_EQ(p.frame().data[2], 0x02);
  PdoUnpacker u(m);
  ASSERT_EQ(u.receive(p.frame()), PdoReceive::ok);
  unsigned v = 0;
  ASSERT_EQ(u.get(3, v), Codec::ok);
  EXPECT_EQ(v, 0xABu);
  bool b = false;
  ASSERT_EQ(u.get(0, b), Codec::ok);
  EXPECT_TRUE(b);
}

TEST(CanopenPdo, ReceiveChecksIdentifierKindAndLength) {
  PdoMapping m = tpdo1();
  PdoUnpacker u(m);
  PdoPacker p(m);
  Frame f = p.frame();
  f.id = 0x184;
  EXPECT_EQ(u.receive(f), PdoReceive::other_identifier);
  f = p.frame();
  f.id |= CAN_RTR_FLAG;
  EXPECT_EQ(u.receive(f), PdoReceive::not_data);
  f = p.frame();
  f.flags = CANFD_FDF;
  EXPECT_EQ(u.receive(f), PdoReceive::not_data);
  f = p.frame();
  f.len = 7;
  EXPECT_EQ(u.receive(f), PdoReceive::wrong_length);
  m.count = 2;  // a 6-byte mapping receiving the 8-byte frame
  PdoUnpacker shorter(m);
  EXPECT_EQ(shorter.receive(p.frame()), PdoReceive::wrong_length);
  EXPECT_FALSE(shorter.has_data());
}

TEST(CanopenPdo, RealsMustBeFinite) {
  PdoMapping m;
  m.kind = PdoKind::tpdo;
  m.cob_id = 0x281;
  m.map({0x2100, 0}, DataType::real32);
  PdoPacker p(m);
  EXPECT_EQ(p.set(0, NAN), Codec::invalid);
  EXPECT_EQ(p.set(0, 1e39), Codec::too_high);
  ASSERT_EQ(p.set(0, 2.5f), Codec::ok);
  Frame f = p.frame();
  PdoUnpacker u(m);
  ASSERT_EQ(u.receive(f), PdoReceive::ok);
  double d = 0;
  ASSERT_EQ(u.get(0, d), Codec::ok);
  EXPECT_EQ(d, 2.5);
  f.data[0] = 0x00;
  f.data[1] = 0x00;
  f.data[2] = 0x80;
  f.data[3] = 0x7F;  // +infinity
  ASSERT_EQ(u.receive(f), PdoReceive::ok);
  EXPECT_EQ(u.get(0, d), Codec::invalid);
}

}  // namespace
