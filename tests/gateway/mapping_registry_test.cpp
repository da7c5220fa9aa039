// A registry of DDS mappings: the core's types from the start; a package's once its module is
// loaded into it (a registry per program: loading into one changes no other) (the teleoperation's, the
// example lab's message type from examples/lab_message); a type that declares its fields carried with one
// registration line, a message whose members differ refused at registration.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "saw/crtk.hpp"
#include "saw/description.hpp"
#include "saw/gateway/fields_conversion.hpp"
#include "saw/gateway/type_map.hpp"
#include "saw/teleop/dds/mappings.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/offset_trajectory.hpp"
#include "saw/teleop/teleop_law.hpp"
#include "saw/value_check.hpp"
#include "saw_msgs/msg/MasterSlavePubSubTypes.h"

namespace {

using saw::gateway::core_mappings;
using saw::gateway::MappingRegistry;

TEST(MappingRegistry, TheCoreTypesAreThereAndAPackagesOnceItsModuleIsLoaded) {
  MappingRegistry r = core_mappings();
  for (auto name : {saw::type_info_of<saw::Pose>().name, saw::type_info_of<saw::OperatingState>().name,
                    saw::type_info_of<saw::ComponentDescription>().name})
    EXPECT_NE(r.find(name), nullptr) << name;
  // The gateway itself knows no teleoperation; the teleop package's module adds its types, and
  // the example lab's module its own (this test is no installed program: both directories are
  // named in $SAW_MAPPING_PATH).
  ASSERT_EQ(setenv("SAW_MAPPING_PATH", SAW_BUILD_MAPPINGS_DIR ":" SAW_EXAMPLE_MAPPINGS_DIR, 1), 0);
  saw::gateway::load_mapping_modules(r);
  const auto* gains = r.find(saw::type_info_of<saw::teleop::Gains>().name);
  ASSERT_NE(gains, nullptr);
  EXPECT_EQ(gains->dds_type(), "saw_msgs::msg::dds_::MasterSlave_");
  const auto* lab = r.find("lab::SpringParams");
  ASSERT_NE(lab, nullptr) << "the example's module, from " << SAW_EXAMPLE_MAPPINGS_DIR;
  EXPECT_EQ(lab->dds_type(), "lab_msgs::msg::dds_::SpringParams_");
  // Registering again (a module loaded twice, a test linking the package) changes nothing.
  const auto before = r.all().size();
  saw::teleop::dds::register_mappings(r);
  EXPECT_EQ(r.all().size(), before);
  EXPECT_EQ(core_mappings().find("lab::SpringParams"), nullptr) << "loaded into that registry, no other";
}

TEST(MappingRegistry, ATypesFieldsTravelWithoutAConversionWrittenByHand) {
  MappingRegistry r = core_mappings();
  saw::teleop::dds::register_mappings(r);
  const auto& m = *r.find(saw::type_info_of<saw::teleop::Gains>().name);
  saw::teleop::Gains g;
  std::string why;
  ASSERT_TRUE(m.from_text("300 250", &g, why)) << why;
  EXPECT_EQ(g.master, 300);
  EXPECT_EQ(g.slave, 250);
  EXPECT_EQ(m.to_text(&g), "300 250");
  EXPECT_FALSE(m.from_text("300", &g, why));
  EXPECT_NE(why.find("expected 2 numbers"), std::string::npos) << why;
  // A peer's sample that is not finite is refused with the reason (the bridge's own check).
  using Conv = saw::gateway::FieldsConv<saw::teleop::Gains, saw_msgs::msg::MasterSlave>;
  saw_msgs::msg::MasterSlave msg;
  msg.master(NAN);
  why.clear();
  EXPECT_FALSE(Conv::from_msg(msg, g, why));
  EXPECT_NE(why.find("not finite"), std::string::npos) << why;
  msg.master(1.5);
  msg.slave(2.5);
  ASSERT_TRUE(Conv::from_msg(msg, g, why)) << why;
  EXPECT_EQ(g.master, 1.5);
  EXPECT_EQ(g.slave, 2.5);
}

// The collaborative law's offset limits and prediction: one registration line each, and a value
// outside the type's own range (its `valid`) refused as the bridge refuses it, before it is sent.
TEST(MappingRegistry, TheCollaborativeLawsOffsetLimitsAndPredictionAreMapped) {
  MappingRegistry r = core_mappings();
  saw::teleop::dds::register_mappings(r);
  const auto* limits = r.find(saw::type_info_of<saw::teleop::OffsetLimits>().name);
  const auto* prediction = r.find(saw::type_info_of<saw::teleop::Prediction>().name);
  ASSERT_NE(limits, nullptr);
  ASSERT_NE(prediction, nullptr);
  EXPECT_EQ(limits->dds_type(), "saw_msgs::msg::dds_::OffsetLimits_");
  EXPECT_EQ(prediction->dds_type(), "saw_msgs::msg::dds_::Prediction_");
  std::string why;
  saw::teleop::OffsetLimits l;
  ASSERT_TRUE(limits->from_text("0.1 1 20", &l, why)) << why;
  EXPECT_EQ(l.velocity, 0.1);
  EXPECT_EQ(l.acceleration, 1);
  EXPECT_EQ(l.jerk, 20);
  EXPECT_EQ(limits->to_text(&l), "0.1 1 20");
  EXPECT_FALSE(limits->from_text("50 1 20", &l, why)) << "a velocity above 10 m/s";
  EXPECT_NE(why.find("outside its type's range"), std::string::npos) << why;
  EXPECT_FALSE(limits->from_text("0.1 0 20", &l, why)) << "a zero acceleration";
  saw::teleop::Prediction p;
  // (after a refusal: the reason of the last one is not taken for this one's)
  ASSERT_TRUE(prediction->from_text("1 0.02 0.01", &p, why)) << why;
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.master_horizon, 0.02);
  EXPECT_EQ(p.slave_horizon, 0.01);
  EXPECT_EQ(prediction->to_text(&p), "1 0.02 0.01");
  EXPECT_FALSE(prediction->from_text("1 2 0", &p, why)) << "a horizon above 1 s";
  EXPECT_FALSE(prediction->from_text("2 0.02 0", &p, why)) << "a flag that is not 0 or 1";
  // The bridge's check is the same: what the gateway lets through, the exporter takes.
  EXPECT_FALSE(saw::check_value(saw::teleop::Prediction{true, -0.1, 0}));
  EXPECT_FALSE(saw::check_value(saw::teleop::OffsetLimits{0.05, 0.5, 1e6}));
  EXPECT_TRUE(saw::check_value(saw::teleop::OffsetLimits{}));
}

// Three numbers where the message has two, and a type with a flag where it has a number.
struct ThreeNumbers {
  static constexpr std::string_view type_name = "test::ThreeNumbers";
  static constexpr std::uint32_t layout_version = 1;
  double a = 0, b = 0, c = 0;
  static constexpr auto fields = std::tuple{&ThreeNumbers::a, &ThreeNumbers::b, &ThreeNumbers::c};
};
struct FlagAndNumber {
  static constexpr std::string_view type_name = "test::FlagAndNumber";
  static constexpr std::uint32_t layout_version = 1;
  bool on = false;
  double x = 0;
  static constexpr auto fields = std::tuple{&FlagAndNumber::on, &FlagAndNumber::x};
};

TEST(MappingRegistry, AMessageWhoseMembersAreNotTheTypesFieldsIsRefusedAtRegistration) {
  saw::gateway::MappingRegistry r;
  try {
    r.add_fields<ThreeNumbers, saw_msgs::msg::MasterSlavePubSubType>();
    FAIL() << "registered";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("test::ThreeNumbers and saw_msgs::msg::dds_::MasterSlave_"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW((r.add_fields<FlagAndNumber, saw_msgs::msg::MasterSlavePubSubType>()), std::invalid_argument);
  EXPECT_TRUE(r.all().empty());
  // The same mapping again is no change.
  r.add_fields<saw::teleop::Gains, saw_msgs::msg::MasterSlavePubSubType>();
  EXPECT_NO_THROW((r.add_fields<saw::teleop::Gains, saw_msgs::msg::MasterSlavePubSubType>()));
  EXPECT_EQ(r.all().size(), 1U);
}

}  // namespace
