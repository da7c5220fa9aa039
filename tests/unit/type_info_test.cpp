// Type names: the same in every compiler's build for registered types, the compiler's otherwise.
#include "saw/type_info.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "saw/crtk.hpp"
#include "saw/task.hpp"

namespace {

using saw::type_info_of;

struct Unregistered {
  double x = 0;
};
enum class UnnamedEnum : std::uint8_t { a, b };

namespace registered {
struct Sample {
  static constexpr std::string_view type_name = "registered::Sample";
  static constexpr std::uint32_t layout_version = 3;
  float a = 0;
};
enum class Mode : std::uint8_t { off, on };
constexpr std::string_view enum_type_name(Mode) { return "registered::Mode"; }
}  // namespace registered

// GCC spells std::int64_t "long int", clang "long": a process built by one must still connect
// to a process built by the other.
TEST(TypeInfo, ArithmeticTypesAreNamedByTheirBytesNotByTheCompilersSpelling) {
  EXPECT_EQ(type_info_of<std::int64_t>().name, "int64");
  EXPECT_EQ(type_info_of<long long>().name, "int64");
  EXPECT_EQ(type_info_of<std::uint64_t>().name, "uint64");
  EXPECT_EQ(type_info_of<std::int32_t>().name, "int32");
  EXPECT_EQ(type_info_of<std::uint32_t>().name, "uint32");
  EXPECT_EQ(type_info_of<std::int16_t>().name, "int16");
  EXPECT_EQ(type_info_of<std::uint16_t>().name, "uint16");
  EXPECT_EQ(type_info_of<std::int8_t>().name, "int8");
  EXPECT_EQ(type_info_of<std::uint8_t>().name, "uint8");
  EXPECT_EQ(type_info_of<double>().name, "float64");
  EXPECT_EQ(type_info_of<float>().name, "float32");
  EXPECT_EQ(type_info_of<bool>().name, "bool");
  EXPECT_EQ(type_info_of<std::int64_t>().version, 1u);
  EXPECT_EQ(type_info_of<long>(), type_info_of<long long>()) << "the same bytes bind";
}

TEST(TypeInfo, ArraysAreNamedByTheirElementAndLength) {
  EXPECT_EQ(type_info_of<saw::Vec3>().name, "array<float64,3>");
  EXPECT_EQ(type_info_of<saw::Quat>().name, "array<float64,4>");
  EXPECT_EQ((type_info_of<std::array<std::uint8_t, 1024>>().name), "array<uint8,1024>");
  EXPECT_EQ((type_info_of<std::array<std::array<std::int32_t, 2>, 10>>().name), "array<array<int32,2>,10>");
  EXPECT_EQ((type_info_of<std::array<saw::Pose, 2>>().name), "array<saw::Pose,2>");
  EXPECT_EQ(type_info_of<saw::Vec3>().version, 1u);
}

TEST(TypeInfo, RegisteredClassesAndEnumsCarryTheirDeclaredNameAndVersion) {
  EXPECT_EQ(type_info_of<saw::Pose>().name, "saw::Pose");
  EXPECT_EQ(type_info_of<saw::JointState>().name, "saw::JointState");
  EXPECT_EQ(type_info_of<saw::TaskStatistics>().name, "saw::TaskStatistics");
  EXPECT_EQ(type_info_of<saw::StateCommand>().name, "saw::StateCommand");
  EXPECT_EQ(type_info_of<saw::OperatingStateValue>().name, "saw::OperatingStateValue");
  EXPECT_EQ(type_info_of<registered::Sample>().name, "registered::Sample");
  EXPECT_EQ(type_info_of<registered::Sample>().version, 3u);
  EXPECT_EQ(type_info_of<registered::Mode>().name, "registered::Mode");
  EXPECT_EQ(type_info_of<registered::Mode>().version, 1u);
  EXPECT_EQ((type_info_of<std::array<registered::Sample, 2>>().version), 3u);
}

// In-process connections keep working with them; the bridge refuses them (version 0).
TEST(TypeInfo, TypesWithoutAStableNameKeepTheCompilersSpellingAndAreNotRegistered) {
  EXPECT_EQ(saw::stable_type_name<Unregistered>(), "");
  EXPECT_NE(type_info_of<Unregistered>().name.find("Unregistered"), std::string_view::npos);
  EXPECT_EQ(type_info_of<Unregistered>().version, 0u);
  EXPECT_NE(type_info_of<UnnamedEnum>().name.find("UnnamedEnum"), std::string_view::npos);
  EXPECT_EQ(type_info_of<UnnamedEnum>().version, 0u);
  EXPECT_EQ(type_info_of<long double>().version, 0u) << "its bytes differ between platforms";
  EXPECT_EQ((type_info_of<std::array<Unregistered, 3>>().version), 0u);
  EXPECT_NE(type_info_of<Unregistered>(), type_info_of<registered::Sample>());
}

// Names are constants: usable where the compiler needs them (static_assert, switch, templates).
static_assert(saw::type_name<std::int64_t>() == "int64");
static_assert(saw::type_name<saw::Vec3>() == "array<float64,3>");
static_assert(saw::layout_version_of<saw::Pose>() == 1);
static_assert(saw::layout_version_of<Unregistered>() == 0);

}  // namespace
