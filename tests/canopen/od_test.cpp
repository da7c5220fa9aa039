// Object dictionary data types: sizes, little-endian encoding, range checks both ways.
#include "saw/canopen/od.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cfloat>
#include <cmath>
#include <limits>

namespace {

using namespace saw::canopen;
using Bytes = std::array<std::uint8_t, 8>;

TEST(CanopenOd, AddressFormatsAsManualsWriteIt) {
  EXPECT_EQ(to_string(ObjectAddress{0x6040, 0}), "0x6040:00");
  EXPECT_EQ(to_string(ObjectAddress{0x1A00, 0x1F}), "0x1A00:1F");
  EXPECT_LT((ObjectAddress{0x1000, 5}), (ObjectAddress{0x1001, 0}));
  EXPECT_LT((ObjectAddress{0x1000, 1}), (ObjectAddress{0x1000, 2}));
}

TEST(CanopenOd, TypesHaveTheirSizesAndNames) {
  EXPECT_EQ(size_of(DataType::boolean), 1u);
  EXPECT_EQ(size_of(DataType::integer16), 2u);
  EXPECT_EQ(size_of(DataType::unsigned24), 3u);
  EXPECT_EQ(size_of(DataType::real32), 4u);
  EXPECT_EQ(size_of(DataType::integer64), 8u);
  EXPECT_EQ(size_of(DataType::real64), 8u);
  EXPECT_EQ(size_of(DataType::visible_string), 0u);
  EXPECT_EQ(size_of(DataType::domain), 0u);
  EXPECT_EQ(to_string(DataType::unsigned16), "UNSIGNED16");
  EXPECT_EQ(data_type_from_code(7), DataType::unsigned32);
  EXPECT_EQ(data_type_from_code(0x0C), std::nullopt);  // TIME_OF_DAY: not supported
  EXPECT_EQ(data_type_from_code(0x17), std::nullopt);  // a gap in the table
  EXPECT_EQ(type_class(DataType::integer40), TypeClass::signed_integer);
  EXPECT_EQ(type_class(DataType::octet_string), TypeClass::bytes);
}

TEST(CanopenOd, IntegersAreLittleEndian) {
  Bytes b{};
  ASSERT_EQ(encode_value(DataType::unsigned32, 0x12345678u, b), Codec::ok);
  EXPECT_EQ(b[0], 0x78);
  EXPECT_EQ(b[1], 0x56);
  EXPECT_EQ(b[2], 0x34);
  EXPECT_EQ(b[3], 0x12);
  ASSERT_EQ(encode_value(DataType::integer16, -2, b), Codec::ok);
  EXPECT_EQ(b[0], 0xFE);
  EXPECT_EQ(b[1], 0xFF);
  std::int32_t v = 0;
  ASSERT_EQ(decode_value(DataType::integer16, std::span(b.data(), 2), v), Codec::ok);
  EXPECT_EQ(v, -2);
  ASSERT_EQ(encode_value(DataType::integer24, -0x800000, b), Codec::ok);
  ASSERT_EQ(decode_value(DataType::integer24, std::span(b.data(), 3), v), Codec::ok);
  EXPECT_EQ(v, -0x800000);
}

TEST(CanopenOd, EveryIntegerWidthRoundTripsItsExtremes) {
  for (DataType t :
       {DataType::integer8, DataType::integer16, DataType::integer24, DataType::integer32,
        DataType::integer40, DataType::integer48, DataType::integer56, DataType::integer64,
        DataType::unsigned8, DataType::unsigned16, DataType::unsigned24, DataType::unsigned32,
        DataType::unsigned40, DataType::unsigned48, DataType::unsigned56, DataType::unsigned64}) {
    for (const Number& n : {type_min(t), type_max(t)}) {
      Bytes b{};
      ASSERT_EQ(encode(t, n, b), Codec::ok) << to_string(t);
      Number back;
      ASSERT_EQ(decode(t, std::span(b.data(), size_of(t)), back), Codec::ok) << to_string(t);
      EXPECT_EQ(compare(back, n), 0) << to_string(t);
    }
  }
}

TEST(CanopenOd, EncodingChecksTheRange) {
  Bytes b{};
  EXPECT_EQ(encode_value(DataType::unsigned8, 255, b), Codec::ok);
  EXPECT_EQ(encode_value(DataType::unsigned8, 256, b), Codec::too_high);
  EXPECT_EQ(encode_value(DataType::unsigned8, -1, b), Codec::too_low);
  EXPECT_EQ(encode_value(DataType::integer8, 127, b), Codec::ok);
  EXPECT_EQ(encode_value(DataType::integer8, 128, b), Codec::too_high);
  EXPECT_EQ(encode_value(DataType::integer8, -129, b), Codec::too_low);
  EXPECT_EQ(encode_value(DataType::integer64, std::numeric_limits<std::uint64_t>::max(), b), Codec::too_high);
  EXPECT_EQ(encode_value(DataType::unsigned64, std::numeric_limits<std::uint64_t>::max(), b), Codec::ok);
  EXPECT_EQ(encode_value(DataType::integer32, 1.5, b), Codec::invalid);
  EXPECT_EQ(encode_value(DataType::integer32, 3.0, b), Codec::ok);
  EXPECT_EQ(encode_value(DataType::boolean, 2, b), Codec::invalid);
  EXPECT_EQ(encode_value(DataType::boolean, true, b), Codec::ok);
  EXPECT_EQ(encode_value(DataType::visible_string, 1, b), Codec::invalid);
  EXPECT_EQ(encode_value(DataType::unsigned32, 1u, std::span(b.data(), 3)), Codec::wrong_length);
}

TEST(CanopenOd, RealsMustBeFiniteAndInRange) {
  Bytes b{};
  ASSERT_EQ(encode_value(DataType::real32, 1.5, b), Codec::ok);
  float f = 0;
  ASSERT_EQ(decode_value(DataType::real32, std::span(b.data(), 4), f), Codec::ok);
  EXPECT_EQ(f, 1.5f);
  EXPECT_EQ(encode_value(DataType::real32, 1e39, b), Codec::too_high);
  EXPECT_EQ(encode_value(DataType::real32, -1e39, b), Codec::too_low);
  EXPECT_EQ(encode_value(DataType::real64, std::nan(""), b), Codec::invalid);
  EXPECT_EQ(encode_value(DataType::real64, INFINITY, b), Codec::invalid);
  ASSERT_EQ(encode_value(DataType::real64, -2.25, b), Codec::ok);
  double d = 0;
  ASSERT_EQ(decode_value(DataType::real64, b, d), Codec::ok);
  EXPECT_EQ(d, -2.25);
  // A NaN arriving from the bus is refused, not passed on.
  const Bytes nan32{0x00, 0x00, 0xC0, 0x7F};
  EXPECT_EQ(decode_value(DataType::real32, std::span(nan32.data(), 4), d), Codec::invalid);
}

TEST(CanopenOd, DecodingChecksLengthAndTarget) {
  const Bytes b{0xFF, 0xFF, 0xFF, 0xFF};
  std::uint32_t u = 0;
  EXPECT_EQ(decode_value(DataType::unsigned32, std::span(b.data(), 3), u), Codec::wrong_length);
  EXPECT_EQ(decode_value(DataType::unsigned32, std::span(b.data(), 5), u), Codec::wrong_length);
  std::int16_t small = 0;
  EXPECT_EQ(decode_value(DataType::unsigned32, std::span(b.data(), 4), small), Codec::too_high);
  std::uint8_t positive = 0;
  EXPECT_EQ(decode_value(DataType::integer8, std::span(b.data(), 1), positive), Codec::too_low);
  bool flag = false;
  EXPECT_EQ(decode_value(DataType::boolean, std::span(b.data(), 1), flag), Codec::invalid);
}

TEST(CanopenOd, CompareIsExactAcrossKinds) {
  EXPECT_EQ(compare(std::int64_t{-1}, std::uint64_t{0}), -1);
  EXPECT_EQ(compare(std::uint64_t{std::numeric_limits<std::uint64_t>::max()}, std::int64_t{0}), 1);
  EXPECT_EQ(compare(2.5, std::int64_t{2}), 1);
  EXPECT_EQ(compare(std::int64_t{7}, std::uint64_t{7}), 0);
  EXPECT_EQ(compare(std::nan(""), 1.0), 2);
}

TEST(CanopenOd, ToValueConvertsDoublesCarefully) {
  std::int64_t i = 0;
  EXPECT_EQ(to_value(Number{9223372036854775808.0}, i), Codec::too_high);
  EXPECT_EQ(to_value(Number{-9223372036854775808.0}, i), Codec::ok);
  EXPECT_EQ(i, std::numeric_limits<std::int64_t>::min());
  std::uint64_t u = 0;
  EXPECT_EQ(to_value(Number{-1.0}, u), Codec::too_low);
  float f = 0;
  EXPECT_EQ(to_value(Number{1e300}, f), Codec::too_high);
}

}  // namespace
