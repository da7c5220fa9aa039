// Plug-ins: a deployment's `plugins:` are loaded before its types are looked up; the example lab
// component (examples/lab_component, built here as a plug-in) runs beside a simulated device;
// a wrong ABI version, a missing file and a library that is no plug-in are file:line errors.
#include "saw/deploy/plugin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "packages.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/teleoperation.hpp"

namespace {

using saw::testing::build;

std::string with_plugin(const std::string& path) {
  return "deployment: {name: p, clock: stepped}\n"
         "plugins: [" +
         path +
         "]\n"
         "components:\n"
         "  - name: device\n"
         "    type: sim_haptic_device\n"
         "    task: {period: 1ms}\n"
         "    params: {hand: {type: sinusoid, amplitude: [0.02, 0, 0], frequency: 0.5}}\n"
         "  - name: spring\n"
         "    type: lab_spring\n"
         "    task: {period: 1ms}\n"
         "    params: {stiffness: 300, max_force: 1.5}\n"
         "connections:\n"
         "  - {client: spring, required: arm, server: device, provided: arm}\n";
}

std::string error_of(const std::string& text) {
  saw::deploy::ComponentRegistry r;  // its own: a failed load must leave no type behind
  saw::testing::register_packages(r);
  try {
    (void)build(text, "cfg.yaml", r);
  } catch (const saw::deploy::ConfigError& e) {
    EXPECT_EQ(r.find("lab_spring"), nullptr);
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

TEST(Plugins, TheExampleLabComponentLoadsAndDrivesASimulatedDevice) {
  saw::deploy::ComponentRegistry r;
  saw::testing::register_packages(r);
  auto d = build(with_plugin(SAW_EXAMPLE_PLUGIN), "cfg.yaml", r);
  ASSERT_NE(r.find("lab_spring"), nullptr);
  EXPECT_EQ(r.find("lab_spring")->origin, SAW_EXAMPLE_PLUGIN);
  d.start();
  d.run_for(1.5);  // the hand at its farthest: sin(2π · 0.5 Hz · 1.5 s) = -1
  d.stop();
  // The spring's force reached the device: its servo_force column is the spring's, not zero.
  const auto* device = d.manager().find("device");
  const auto* spring = d.manager().find("spring");
  ASSERT_NE(spring, nullptr);
  const int servo = device->state_table().find_column("servo_force");
  const int force = spring->state_table().find_column("force");
  ASSERT_GE(servo, 0);
  ASSERT_GE(force, 0);
  saw::Vec3 applied{}, sent{};
  ASSERT_EQ(device->state_table().read_latest_erased(static_cast<std::uint32_t>(servo), &applied, nullptr),
            saw::Status::ok);
  ASSERT_EQ(spring->state_table().read_latest_erased(static_cast<std::uint32_t>(force), &sent, nullptr),
            saw::Status::ok);
  EXPECT_GT(std::abs(sent[0]), 0.5) << "the hand drags the device up to 2 cm away: the spring pulls";
  EXPECT_LE(std::hypot(sent[0], sent[1], sent[2]), 1.5 + 1e-9) << "clipped to max_force";
  EXPECT_NEAR(applied[0], sent[0], 0.2) << "the device applies what the spring sent (one cycle later)";
}

// A lab's law (examples/lab_law): one file, registered by its plug-in, chosen with `law:`, its
// settings checked and commanded like the built-in laws'.
TEST(Plugins, TheExampleLabLawRunsOnTheTeleoperationTask) {
  const std::string text = std::string("deployment: {name: p, clock: stepped}\n") + "plugins: [" +
                           SAW_EXAMPLE_LAW_PLUGIN +
                           "]\n"
                           "components:\n"
                           "  - name: master\n"
                           "    type: sim_haptic_device\n"
                           "    task: {period: 1ms}\n"
                           "    params: {hand: {type: sinusoid, amplitude: [0.02, 0, 0], frequency: 0.5}}\n"
                           "  - name: slave\n"
                           "    type: sim_haptic_device\n"
                           "    task: {period: 1ms}\n"
                           "  - name: teleop\n"
                           "    type: teleop\n"
                           "    task: {period: 1ms}\n"
                           "    params: {law: lab_coupling, stiffness: 300, feedback: 0.5}\n"
                           "connections:\n"
                           "  - {client: teleop, required: master, server: master, provided: arm}\n"
                           "  - {client: teleop, required: slave, server: slave, provided: arm}\n";
  saw::deploy::ComponentRegistry r;
  saw::testing::register_packages(r);
  auto d = build(text, "cfg.yaml", r);
  ASSERT_NE(saw::teleop::laws(r).find("lab_coupling"), nullptr) << "in the registry the plug-in was given";
  saw::deploy::ComponentRegistry other;
  saw::testing::register_packages(other);
  EXPECT_EQ(saw::teleop::laws(other).find("lab_coupling"), nullptr)
      << "and in no other: no process-wide state";
  auto* t = d.find<saw::teleop::Teleoperation>("teleop");
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->law_name(), "lab_coupling");
  EXPECT_NE(t->provided("teleop")->find_command("set_feedback"), nullptr) << "its settings are commands";
  const auto* energy = t->provided("teleop")->find_command("energy");
  ASSERT_NE(energy, nullptr) << "its read-outs are read commands";
  d.start();
  d.run_for(1.5);
  d.stop();
  EXPECT_EQ(t->operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_GT(t->enabled_cycles(), 1400u);
  EXPECT_GT(t->tracking_max(), 0.0) << "the master moved";
  EXPECT_LT(t->tracking_rms(), 0.01) << "the slave follows the master";
  double work = 0;
  ASSERT_EQ(energy->read(nullptr, &work), saw::Status::ok);
  EXPECT_TRUE(std::isfinite(work) && work != 0.0) << work;
  // A setting out of its declared bounds is a file:line error like any other.
  std::string bad = text;
  bad.replace(bad.find("feedback: 0.5"), 13, "feedback: 2");
  try {
    (void)build(bad, "cfg.yaml", r);
    ADD_FAILURE() << "feedback 2 accepted";
  } catch (const saw::deploy::ConfigError& e) {
    EXPECT_TRUE(std::regex_search(
        e.what(), std::regex(R"(^cfg\.yaml:14:\d+: key 'components\[2\]\.params\.feedback')")))
        << e.what();
  }
}

// A lab's law that needs an input no built-in law reads (examples/lab_force_law): declared in its
// one file, required, read and handed over by the task; the operator feels the slave's sensor.
TEST(Plugins, TheExampleForceSensorLawGetsTheSlavesWrenchByDeclaringIt) {
  const std::string text = std::string("deployment: {name: p, clock: stepped}\n") + "plugins: [" +
                           SAW_EXAMPLE_FORCE_LAW_PLUGIN +
                           "]\n"
                           "components:\n"
                           "  - name: master\n"
                           "    type: sim_haptic_device\n"
                           "    task: {period: 1ms}\n"
                           "    params: {hand: {type: sinusoid, amplitude: [0, 0, 0.02], frequency: 0.5}}\n"
                           "  - name: slave\n"
                           "    type: sim_haptic_device\n"
                           "    task: {period: 1ms}\n"
                           "    params: {wall: {point: [0, 0, -0.01], normal: [0, 0, 1], stiffness: 300}}\n"
                           "  - name: teleop\n"
                           "    type: teleop\n"
                           "    task: {period: 1ms}\n"
                           "    params: {law: force_sensor_feedback, stiffness: 300, feedback: 1.0}\n"
                           "connections:\n"
                           "  - {client: teleop, required: master, server: master, provided: arm}\n"
                           "  - {client: teleop, required: slave, server: slave, provided: arm}\n";
  saw::deploy::ComponentRegistry r;
  saw::testing::register_packages(r);
  auto d = build(text, "cfg.yaml", r);
  auto* t = d.find<saw::teleop::Teleoperation>("teleop");
  auto* master = d.find<saw::drivers::SimHapticDevice>("master");
  auto* slave = d.find<saw::drivers::SimHapticDevice>("slave");
  ASSERT_TRUE(t != nullptr && master != nullptr && slave != nullptr);
  d.start();
  d.run_for(1.5);  // the hand at its lowest: the slave pressed into the wall
  EXPECT_EQ(t->operating_state(), saw::OperatingStateValue::enabled) << t->fault_reason();
  const double wall = slave->wall_force().z();
  double sensed = -1;
  const auto* sensed_read = t->provided("teleop")->find_command("sensed_force");
  ASSERT_NE(sensed_read, nullptr) << "its read-out";
  ASSERT_EQ(sensed_read->read(nullptr, &sensed), saw::Status::ok);
  EXPECT_GT(wall, 0.5) << "the slave pushes into its wall";
  EXPECT_NEAR(sensed, wall, 0.05) << "the law read the slave's measured_cf (a cycle earlier)";
  EXPECT_NEAR(master->applied_force().z(), wall, 0.05) << "the operator feels it (feedback 1)";
  d.stop();
}

TEST(Plugins, AWrongAbiVersionIsAFileErrorNamingBothVersions) {
  const auto message = error_of(with_plugin(SAW_WRONG_ABI_PLUGIN));
  const auto v = std::to_string(saw::deploy::plugin_abi_version);
  const auto w = std::to_string(saw::deploy::plugin_abi_version + 1);
  EXPECT_TRUE(
      std::regex_search(message, std::regex(R"(^cfg\.yaml:2:\d+: key 'plugins\[0\]': plug-in not loaded: )")))
      << message;
  EXPECT_NE(message.find("ABI version " + w + "; this program has ABI version " + v), std::string::npos)
      << message;
}

TEST(Plugins, AMissingFileAndALibraryThatIsNoPluginAreFileErrors) {
  auto message = error_of(with_plugin("/nonexistent/liblab.so"));
  EXPECT_TRUE(std::regex_search(
      message,
      std::regex(R"(^cfg\.yaml:2:\d+: key 'plugins\[0\]': .*no such file: /nonexistent/liblab\.so)")))
      << message;
  message = error_of(with_plugin(SAW_NOT_A_PLUGIN));
  EXPECT_TRUE(std::regex_search(
      message, std::regex(R"(^cfg\.yaml:2:\d+: key 'plugins\[0\]': .*is not a sawrt plug-in)")))
      << message;
  // Relative paths are the file's directory's: "cfg.yaml" is in the working directory.
  message = error_of(with_plugin("lib/liblab.so"));
  EXPECT_NE(message.find("no such file: lib/liblab.so"), std::string::npos) << message;
}

TEST(Plugins, ATypeNameTakenAlreadyIsRefusedNamingBothOrigins) {
  saw::deploy::ComponentRegistry r;
  r.add(
      "lab_spring", "a built-in type of the same name",
      [](const saw::deploy::ComponentContext&, saw::deploy::Params&) { return 0; },
      [](const std::string&, const int&) { return std::unique_ptr<saw::Component>(); });
  try {
    r.load_plugin(SAW_EXAMPLE_PLUGIN);
    ADD_FAILURE() << "registered twice";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("'lab_spring' registered twice (built in, then by " +
                                         std::string(SAW_EXAMPLE_PLUGIN) + ")"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
