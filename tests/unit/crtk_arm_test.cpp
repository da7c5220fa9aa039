// The CRTK arm declaration: one name and type per member, for devices and clients alike.
#include "saw/crtk_arm.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <string>

#include "core_fixtures.hpp"

namespace {

namespace crtk = saw::crtk;
namespace arm = saw::crtk::arm;

// A client cannot ask for a member with a function of another type: it does not compile.
template <class M, class F>
concept Requirable = requires(saw::RequiredInterface& r, M m, F& f) {
  crtk::require(r, m, f);
};
static_assert(Requirable<crtk::Read<saw::Pose>, saw::FunctionRead<saw::Pose>>);
static_assert(!Requirable<crtk::Read<saw::Pose>, saw::FunctionRead<saw::Twist>>);
static_assert(!Requirable<crtk::Write<saw::Wrench>, saw::FunctionRead<saw::Wrench>>);
static_assert(!Requirable<crtk::Write<saw::Wrench>, saw::FunctionWrite<saw::Vec3>>);

TEST(CrtkArm, EveryMemberIsRegisteredForOtherProcessesAndNamedOnce) {
  std::set<std::string> commands, events;
  for (const auto& m : arm::members) {
    EXPECT_NE(m.signature.arg.version, 0u) << m.name << " must be able to cross a process boundary";
    EXPECT_TRUE((saw::is_event(m.signature.kind) ? events : commands).emplace(m.name).second) << m.name;
  }
  EXPECT_TRUE(commands.count("measured_js") == 1 && events.count("operating_state") == 1);
}

class Device : public saw::Task {
 public:
  Device() : Task("device", saw::testing::one_ms()) {
    auto& p = provide(std::string(arm::interface_name));
    crtk::provide(p, arm::measured_cp, state_table(), &pose);
    crtk::provide(p, arm::servo_cf, [this](const saw::Wrench& w) { force = w.force; });
    state_event = &crtk::provide(p, arm::operating_state_event);
  }
  void run() override {}
  saw::Pose pose;
  saw::Vec3 force{};
  saw::EventWrite<saw::OperatingState>* state_event;
};

class User : public saw::Task {
 public:
  User() : Task("user", saw::testing::one_ms()) {
    auto& r = require("arm");
    crtk::require(r, arm::measured_cp, cp);
    crtk::require(r, arm::servo_cf, cf);
    crtk::require(r, arm::operating_state_event, [this](const saw::OperatingState& s) { state = s.state; });
  }
  void run() override {}
  saw::FunctionRead<saw::Pose> cp;
  saw::FunctionWrite<saw::Wrench> cf;
  saw::OperatingStateValue state = saw::OperatingStateValue::disabled;
};

TEST(CrtkArm, ADeviceProvidingItAndAClientRequiringItConnect) {
  Device d;
  User u;
  saw::Manager m;
  m.add(d);
  m.add(u);
  m.connect("user", "arm", "device", std::string(arm::interface_name));
  m.start_stepped();
  d.pose.position = {1, 2, 3};
  m.step();
  saw::Pose p;
  ASSERT_EQ(u.cp(p), saw::Status::ok);
  EXPECT_EQ(p.position, (saw::Vec3{1, 2, 3}));
  ASSERT_EQ(u.cf(saw::Wrench{{4, 5, 6}, {}}), saw::Status::ok);
  m.step();
  EXPECT_EQ(d.force, (saw::Vec3{4, 5, 6}));
  m.stop();
}

TEST(JointState, NamesAreBoundedTerminatedAndGivenForAllJointsOrNone) {
  saw::JointState j;
  j.size = 2;
  EXPECT_TRUE(saw::check_value(j)) << "no names at all is valid (ROS: an empty name list)";
  ASSERT_TRUE(j.set_name(0, "outer_yaw"));
  EXPECT_FALSE(saw::check_value(j)) << "joint 1 has a position but no name";
  ASSERT_TRUE(j.set_name(1, std::string(saw::JointState::max_name, 'n')));
  EXPECT_TRUE(saw::check_value(j));
  EXPECT_EQ(j.name_of(0), "outer_yaw");
  EXPECT_EQ(j.name_of(1).size(), saw::JointState::max_name);

  EXPECT_FALSE(j.set_name(1, std::string(saw::JointState::max_name + 1, 'n'))) << "too long: refused";
  EXPECT_EQ(j.name_of(1).size(), saw::JointState::max_name) << "unchanged";
  EXPECT_FALSE(j.set_name(saw::JointState::max_joints, "x"));
  EXPECT_FALSE(j.set_name(0, std::string_view("a\0b", 3)));

  saw::JointState extra = j;
  ASSERT_TRUE(extra.set_name(2, "beyond_size"));
  EXPECT_FALSE(saw::check_value(extra)) << "at most `size` names";

  // Bytes from another process: a name filling its field without a NUL is refused.
  saw::JointState unterminated = j;
  std::memset(unterminated.name[1].data(), 'z', unterminated.name[1].size());
  EXPECT_FALSE(saw::check_value(unterminated));
}

}  // namespace

// Declared limits mean one thing wherever they are checked (the bridge, the gateway, sawctl):
// every floating-point number of the value, and an integer value itself, but not a struct's
// counts.
TEST(ValueCheck, LimitsBoundEveryQuantityButNotACount) {
  const saw::Limits l{-2, 2};
  saw::Pose p;
  p.position = {1, -1, 0.5};
  EXPECT_TRUE(saw::check_value(p, &l));
  const saw::Limits tight{-0.5, 0.5};  // the position fits; the identity quaternion's w = 1 does not
  p.position = {0.1, 0.1, 0.1};
  EXPECT_FALSE(saw::check_value(p, &tight)) << "a pose's orientation is bounded as much as its position";
  EXPECT_TRUE(saw::check_value(std::int64_t{2}, &l));
  EXPECT_FALSE(saw::check_value(std::int64_t{3}, &l)) << "an integer argument is a quantity";
  saw::JointState j;
  j.size = 6;  // more joints than the bound: a count, not bounded
  EXPECT_TRUE(saw::check_value(j, &l));
  j.position[4] = 2.5;
  EXPECT_FALSE(saw::check_value(j, &l));
}
