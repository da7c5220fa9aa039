// The seam between the teleoperation task and its laws: a second law (position-position) on
// the same task, settings declared once (commands, bounds, read-back), the registry, the
// description a client finds the task by, and the docs table kept equal to the declarations.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/laws/position_position.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/teleop_rig.hpp"
#include "teleop_support.hpp"

namespace {

using saw::Status;
using saw::teleop::PositionPositionLaw;
using saw::testing::norm;

// Calls the position-position law's commands and reads its settings back, from its own thread.
class PpOperator : public saw::Component {
 public:
  PpOperator() : Component("operator") {
    auto& r = require("teleop");
    r.add_function("set_scale", set_scale);
    r.add_function("set_stiffness", set_stiffness);
    r.add_function("stiffness", stiffness);
    r.add_function("scale", scale);
    r.add_function("description", description);
  }
  saw::FunctionWrite<double> set_scale, set_stiffness;
  saw::FunctionRead<double> stiffness, scale;
  saw::FunctionRead<saw::ComponentDescription> description;
};

using PpRig = saw::testing::TeleopRig<PpOperator>;

PositionPositionLaw::Settings pp_settings() {
  PositionPositionLaw::Settings s;
  s.stiffness = 100;
  s.force_limit = 10;
  return s;
}

TEST(PositionPositionLaw, TheSlaveTracksTheMasterAndTheMasterFeelsNothing) {
  PpRig rig(saw::teleop::TeleopConfig{}, saw::teleop::law_spec<PositionPositionLaw>(pp_settings()));
  rig.master.position = {0.05, 0.01, 0};
  rig.slave.position = {-0.02, 0.03, 0.01};
  rig.step(3);
  EXPECT_EQ(rig.teleop.law_name(), "position_position");
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "engaging with the devices apart makes no force";
  rig.master.position[0] += 0.01;
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[0], 1.0, 1e-9) << "k·1 cm toward the master's motion";
  EXPECT_EQ(norm(rig.master.force), 0.0) << "no force feedback";
  rig.slave.position[0] += 0.01;  // the slave got there: no error, no force
  rig.step(2);
  EXPECT_LT(norm(rig.slave.force), 1e-9);
  EXPECT_LT(rig.teleop.tracking_max(), 0.0101);
}

TEST(PositionPositionLaw, ItsSettingsAreCommandsReadBackAndBounded) {
  PpRig rig(saw::teleop::TeleopConfig{}, saw::teleop::law_spec<PositionPositionLaw>(pp_settings()));
  rig.master.position = {0.1, 0, 0};
  rig.step(3);
  ASSERT_EQ(rig.op.set_stiffness(200), Status::ok);
  ASSERT_EQ(rig.op.set_stiffness(1e9), Status::ok);  // beyond max_gain: refused
  ASSERT_EQ(rig.op.set_scale(0.5), Status::ok);
  rig.step(2);
  EXPECT_EQ(rig.teleop.rejected_commands(), 1u);
  double k = 0, s = 0;
  ASSERT_EQ(rig.op.stiffness(k), Status::ok);
  ASSERT_EQ(rig.op.scale(s), Status::ok);
  EXPECT_EQ(k, 200);
  EXPECT_EQ(s, 0.5);
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "a rescale does not step the force";
  rig.master.position[0] += 0.02;  // 2 cm of master asks 1 cm of the slave: 200 N/m · 1 cm
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[0], 2.0, 1e-9);
  // The bounds are declared to the bridge and the gateway too.
  const auto* cmd = rig.teleop.provided("teleop")->find_command("set_stiffness");
  ASSERT_NE(cmd, nullptr);
  ASSERT_TRUE(cmd->limits.has_value());
  EXPECT_EQ(cmd->limits->max, saw::teleop::max_gain);
}

TEST(PositionPositionLaw, TheTaskStillOwnsClutchAndFaults) {
  saw::teleop::TeleopConfig c;
  c.stale_timeout = 0.005;
  PpRig rig(c, saw::teleop::law_spec<PositionPositionLaw>(pp_settings()));
  rig.step(3);
  rig.master.press_clutch(true);
  rig.step(1);
  rig.master.position[1] += 0.05;
  rig.step(3);
  EXPECT_EQ(norm(rig.slave.force), 0.0);
  rig.master.press_clutch(false);
  rig.step(2);
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "releasing the clutch does not jump";
  rig.step(8, false);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, saw::FaultCode::input_stale);
  EXPECT_EQ(norm(rig.slave.force), 0.0);
}

// A PSM follows a pose, not a force: the law's goal, at the slave's orientation when it engaged.
TEST(PositionPositionLaw, ASlaveThatFollowsAPoseGetsGoalsWithoutAStep) {
  saw::teleop::TeleopConfig c;
  c.slave_servo_cp = true;
  PpRig rig(c, saw::teleop::law_spec<PositionPositionLaw>(pp_settings()));
  rig.master.position = {0.05, 0.01, 0};
  rig.slave.position = {-0.02, 0.03, 0.01};
  const saw::Quat turned{0, 0, std::sin(0.25), std::cos(0.25)};
  rig.slave.orientation = turned;
  rig.step(3);
  ASSERT_GT(rig.slave.goals, 0) << "the slave gets goals";
  EXPECT_EQ(rig.slave.commands, 0) << "and no force";
  EXPECT_LT(saw::testing::dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "engaging: no step";
  EXPECT_EQ(rig.slave.goal.orientation, turned);
  rig.master.position[0] += 0.01;
  rig.slave.orientation = {0, 0, 0, 1};  // the slave turning does not turn its goal
  rig.step(2);
  EXPECT_NEAR(rig.slave.goal.position[0], -0.01, 1e-12) << "the master's 1 cm, scale 1";
  EXPECT_EQ(rig.slave.goal.orientation, turned);
  // Clutched, nothing is sent (the device's watchdog holds the arm); released, no step.
  rig.master.press_clutch(true);
  rig.step(1);
  const int before = rig.slave.goals;
  rig.master.position[1] += 0.05;
  rig.slave.position = {0.0, 0.0, 0.0};
  rig.step(3);
  EXPECT_EQ(rig.slave.goals, before) << "no goal while clutched";
  rig.master.press_clutch(false);
  rig.step(2);
  EXPECT_GT(rig.slave.goals, before);
  EXPECT_LT(norm(rig.slave.goal.position), 1e-12) << "releasing the clutch: the goal is where the slave is";
}

TEST(TeleopSeam, TheTaskDescribesItselfAndItsRoles) {
  PpRig rig(saw::teleop::TeleopConfig{}, saw::teleop::law_spec<PositionPositionLaw>(pp_settings()));
  rig.step(1);
  saw::ComponentDescription d;
  ASSERT_EQ(rig.op.description(d), Status::ok);
  using D = saw::ComponentDescription;
  EXPECT_EQ(D::get(d.kind), "teleoperation");
  EXPECT_EQ(D::get(d.variant), "position_position");
  EXPECT_EQ(D::get(d.roles[0]), "master");
  EXPECT_EQ(D::get(d.servers[0]), "master.arm");
  EXPECT_EQ(D::get(d.roles[1]), "slave");
  EXPECT_EQ(D::get(d.servers[1]), "slave.arm");
  // The law's declared settings, in declaration order, as a client builds its forms from them.
  ASSERT_EQ(d.setting_count, std::tuple_size_v<decltype(PositionPositionLaw::declared_settings)>);
  EXPECT_EQ(D::get(d.settings[0].name), "scale");
  EXPECT_EQ(D::get(d.settings[1].name), "stiffness");
  EXPECT_EQ(D::get(d.settings[1].unit), "N/m");
  EXPECT_EQ(d.settings[1].min, 0.0);
  EXPECT_EQ(d.settings[1].max, saw::teleop::max_gain);
  EXPECT_EQ(d.settings[1].count, 1U);
  EXPECT_TRUE(d.settings[1].command);
}

const saw::teleop::LawRegistry& builtin_laws() {
  static const saw::teleop::LawRegistry r = [] {
    saw::teleop::LawRegistry x;
    saw::teleop::add_builtin_laws(x);
    return x;
  }();
  return r;
}

TEST(TeleopSeam, TheCollaborativeLawDescribesTheShapeOfItsSettings) {
  saw::testing::Rig rig(saw::testing::basic());
  saw::ComponentDescription d;
  d = rig.teleop.description();
  using D = saw::ComponentDescription;
  const auto& rows = builtin_laws().find("collaborative")->rows;
  ASSERT_EQ(d.setting_count, rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    SCOPED_TRACE(rows[i].name);
    EXPECT_EQ(D::get(d.settings[i].name), rows[i].name);
    EXPECT_EQ(D::get(d.settings[i].unit), rows[i].unit);
    EXPECT_EQ(d.settings[i].command, !rows[i].command.empty());
  }
  const auto at = [&](std::string_view n) {
    for (std::size_t i = 0; i < d.setting_count; ++i)
      if (D::get(d.settings[i].name) == n) return d.settings[i];
    return saw::DeclaredSetting{};
  };
  EXPECT_EQ(at("gains").count, 2U);
  EXPECT_EQ(at("gains").max, saw::teleop::max_gain);
  EXPECT_EQ(at("slave_offset").count, 3U);
  EXPECT_EQ(at("scale").count, 1U);
  EXPECT_FALSE(at("ratchet").command);
}

// Every setting the component accepts is published; each command setting is set_<name>.
TEST(TeleopSeam, EveryDeclaredSettingIsReadBackAndEveryCommandBounded) {
  saw::testing::Rig rig(saw::testing::basic());
  const auto* p = rig.teleop.provided("teleop");
  const auto& entry = *builtin_laws().find("collaborative");
  for (const auto& row : entry.rows) {
    SCOPED_TRACE(row.name);
    const auto* read = p->find_command(row.name);
    ASSERT_NE(read, nullptr);
    EXPECT_EQ(read->signature.kind, saw::CommandKind::read);
    const auto* write = p->find_command("set_" + row.name);
    EXPECT_EQ(write != nullptr, !row.command.empty());
  }
  // The GUI's and the tests' command names are the declared ones.
  for (const char* n : {"set_scale", "set_gains", "set_force_limits", "set_prediction", "set_slave_offset"})
    EXPECT_NE(p->find_command(n), nullptr) << n;
  ASSERT_TRUE(p->find_command("set_gains")->limits.has_value());
  EXPECT_EQ(p->find_command("set_gains")->limits->max, saw::teleop::max_gain);
  // A setting set is what is read back; a refused one leaves it.
  ASSERT_EQ(rig.op.set_gains({250, 150}), Status::ok);
  ASSERT_EQ(rig.op.set_gains({-1, 150}), Status::ok);
  rig.step(2);
  saw::teleop::Gains g;
  ASSERT_EQ(p->find_command("gains")->read(nullptr, &g), Status::ok);
  EXPECT_EQ(g.master, 250);
  EXPECT_EQ(g.slave, 150);
  EXPECT_EQ(rig.teleop.rejected_commands(), 1u);
}

// A law a lab writes registers with one line; a setting may not take the task's own names.
struct SpringLaw {
  struct Settings {
    double stiffness = 50;
  };
  static constexpr std::string_view name = "spring_test", description = "a test spring on the slave";
  static constexpr auto declared_settings = std::tuple{
      saw::teleop::Setting<Settings, double>{"stiffness", "N/m", 0, 1000, &Settings::stiffness, "k"}};
  SpringLaw(const Settings& s, const saw::teleop::LawContext&) : s_(s) {}
  Settings& settings() noexcept { return s_; }
  void reset(const saw::teleop::LawInputs&) noexcept {}
  saw::teleop::LawCommand step(const saw::teleop::LawInputs& in) noexcept {
    saw::teleop::LawCommand out;
    out.slave_force = -s_.stiffness * in.slave.position;
    pull_ = out.slave_force.norm();
    return out;
  }
  Settings s_;
  double pull_ = 0;
  static constexpr auto declared_readouts =
      std::tuple{saw::teleop::Readout<SpringLaw, double>{"pull", "N", &SpringLaw::pull_, "|f_s|"}};
};

struct BadLaw : SpringLaw {
  static constexpr std::string_view name = "bad_test";
  static constexpr auto declared_settings = std::tuple{
      saw::teleop::Setting<Settings, double>{"stale_timeout", "s", 0, 1, &Settings::stiffness, "clashes"}};
  using SpringLaw::SpringLaw;
};

struct SameNameLaw : SpringLaw {
  static constexpr std::string_view name = "spring_test";
  using SpringLaw::SpringLaw;
};

// Connected to the task, calling nothing of it (any law's interface).
class Bystander : public saw::Component {
 public:
  Bystander() : Component("operator") {
    auto& r = require("teleop");
    r.add_function("state_command", state_command);
  }
  saw::FunctionWrite<saw::StateCommand> state_command;
};

TEST(TeleopSeam, ALawsReadOutsAreTheTasksState) {
  saw::testing::TeleopRig<Bystander> rig(saw::teleop::TeleopConfig{}, saw::teleop::law_spec<SpringLaw>());
  rig.slave.position = {0.01, 0, 0};
  rig.step(3);
  const auto* pull = rig.teleop.provided("teleop")->find_command("pull");
  ASSERT_NE(pull, nullptr);
  double v = 0;
  ASSERT_EQ(pull->read(nullptr, &v), Status::ok);
  EXPECT_NEAR(v, 0.5, 1e-12) << "50 N/m · 1 cm";
  EXPECT_NEAR(rig.slave.force[0], -0.5, 1e-12);
}

TEST(TeleopSeam, ALawRegistersWithOneLineAndMayNotShadowTheTasksKeys) {
  saw::teleop::LawRegistry r;
  r.add<SpringLaw>();
  ASSERT_NE(r.find("spring_test"), nullptr);
  EXPECT_EQ(r.find("spring_test")->rows.at(0).command, "set_stiffness");
  EXPECT_NO_THROW(r.add<SpringLaw>()) << "the same law again (a plug-in loaded again)";
  EXPECT_THROW(r.add<SameNameLaw>(), std::invalid_argument) << "another law under a taken name";
  EXPECT_THROW(r.add<BadLaw>(), std::invalid_argument);
}

// docs/teleop-laws.md carries the settings tables as generated from the declarations;
// `SAW_UPDATE_DOCS=1 saw_teleop_tests --gtest_filter=TeleopSeam.TheDocsTableIsTheDeclarations`
// rewrites that part.
TEST(TeleopSeam, TheDocsTableIsTheDeclarations) {
  const char* path = SAW_SOURCE_DIR "/docs/teleop-laws.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << "docs/teleop-laws.md is missing";
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const std::string begin = "<!-- generated: law settings -->\n", end = "<!-- end generated -->";
  const auto b = doc.find(begin), e = doc.find(end);
  ASSERT_TRUE(b != std::string::npos && e != std::string::npos && b < e) << "markers missing";
  const std::string expected = builtin_laws().markdown();
  if (std::getenv("SAW_UPDATE_DOCS") != nullptr) {
    in.close();
    std::ofstream(path) << doc.substr(0, b + begin.size()) << expected << doc.substr(e);
    return;
  }
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), expected)
      << "docs/teleop-laws.md is out of date; its generated part should read:\n"
      << expected;
}

}  // namespace
