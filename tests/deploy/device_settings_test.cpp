// The device base's keys: read once for every driver, one range per key, each error at its line.
#include "saw/deploy/device_settings.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

using namespace std::chrono_literals;
using saw::deploy::ConfigError;
using saw::deploy::DeviceKeys;
using saw::deploy::Params;
using saw::deploy::parse_device_settings;

const saw::TaskConfig task = saw::TaskConfig::periodic(1ms, 0);

// The settings `text` (a YAML mapping, line 1) gives over the defaults, every key read.
saw::DeviceSettings parsed(const std::string& text, const DeviceKeys& keys = {}, saw::DeviceSettings d = {}) {
  const Params p(YAML::Load(text), "dev.yaml", "params");
  d = parse_device_settings(p, task, keys, d);
  p.check_all_used();
  return d;
}

std::string error_of(const std::string& text, const DeviceKeys& keys = {}) {
  try {
    (void)parsed(text, keys);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(DeviceSettings, EachKeyIsReadInItsOneRange) {
  const auto s = parsed(
      "{max_force: 5, command_timeout: 20ms, on_command_timeout: fault, start_enabled: false, "
      "enable_timeout: 2s, home_timeout: 30s, workspace: {min: [-1, -1, -1], max: [1, 1, 0]}, "
      "max_linear_speed: 0.1, max_angular_speed: 1}",
      {.homes = true, .poses = true});
  EXPECT_EQ(s.max_force, 5);
  EXPECT_EQ(s.command_timeout, 20'000'000);
  EXPECT_TRUE(s.fault_on_command_timeout);
  EXPECT_FALSE(s.start_enabled);
  EXPECT_EQ(s.enable_timeout, 2'000'000'000);
  EXPECT_EQ(s.home_timeout, 30'000'000'000);
  EXPECT_EQ(s.workspace_max[2], 0);
  EXPECT_EQ(s.max_linear_speed, 0.1);
  EXPECT_EQ(s.max_angular_speed, 1);
  // Absent: the driver's defaults, the command watchdog at 3 periods.
  const auto d = parsed("{}", {}, {.max_force = 8, .start_enabled = false});
  EXPECT_EQ(d.max_force, 8);
  EXPECT_FALSE(d.start_enabled);
  EXPECT_EQ(d.command_timeout, 3'000'000);
}

TEST(DeviceSettings, AValueOutOfItsRangeIsAnErrorAtItsLineNamingTheKey) {
  const DeviceKeys all{.most_force = 20, .homes = true, .poses = true};
  for (const auto& [text, key, what] :
       std::initializer_list<std::tuple<std::string, std::string, std::string>>{
           {"{max_force: 0}", "max_force", "(0, 20] N"},
           {"{max_force: 21}", "max_force", "(0, 20] N"},
           {"{command_timeout: 500us}", "command_timeout", "at least one period"},
           {"{command_timeout: 11s}", "command_timeout", "at most 10 s"},
           {"{on_command_timeout: stop}", "on_command_timeout", "hold, fault"},
           {"{enable_timeout: 61s}", "enable_timeout", "at most 60 s"},
           {"{home_timeout: 0}", "home_timeout", "at least one period"},
           {"{workspace: {min: [0, 0, 0], max: [1, 1, 0]}}", "workspace.max", "above min"},
           {"{max_linear_speed: 3}", "max_linear_speed", "out of range"},
           {"{max_angular_speed: 0}", "max_angular_speed", "out of range"},
       }) {
    const std::string e = error_of("\n" + text, all);
    EXPECT_NE(e.find("dev.yaml:2"), std::string::npos) << text << " → " << e;
    EXPECT_NE(e.find(key), std::string::npos) << text << " → " << e;
    EXPECT_NE(e.find(what), std::string::npos) << text << " → " << e;
  }
}

// A key the driver's hardware does not take is not silently dropped: an unknown key at its line.
TEST(DeviceSettings, AKeyTheHardwareDoesNotTakeIsAnUnknownKey) {
  EXPECT_NE(error_of("{max_force: 3}", {.force = false}).find("max_force"), std::string::npos);
  EXPECT_NE(error_of("{home_timeout: 1s}").find("home_timeout"), std::string::npos);
  EXPECT_NE(error_of("{max_linear_speed: 0.1}").find("max_linear_speed"), std::string::npos);
  EXPECT_NE(error_of("{workspace: {min: [0, 0, 0], max: [1, 1, 1]}}").find("workspace"), std::string::npos);
  EXPECT_NE(error_of("{enable_timeout: 1s}", {.enable_timeout = false}).find("enable_timeout"),
            std::string::npos);
  EXPECT_EQ(error_of("{workspace: {min: [0, 0, 0], max: [1, 1, 1]}}", {.workspace = true}), "no error");
}

}  // namespace
