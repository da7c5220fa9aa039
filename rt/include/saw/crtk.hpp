// CRTK value types (poses, twists, wrenches, joint states, operating states) as Plain structs.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace saw {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // x, y, z, w (ROS order)

// geometry_msgs/Pose; the stamp is the state-table row's.
struct Pose {
  static constexpr std::uint32_t layout_version = 1;
  Vec3 position{};
  Quat orientation{0, 0, 0, 1};
};

// geometry_msgs/Twist.
struct Twist {
  static constexpr std::uint32_t layout_version = 1;
  Vec3 linear{};
  Vec3 angular{};
};

// geometry_msgs/Wrench.
struct Wrench {
  static constexpr std::uint32_t layout_version = 1;
  Vec3 force{};
  Vec3 torque{};
};

// sensor_msgs/JointState with a fixed maximum size (a da Vinci MTM has 7 joints + gripper).
struct JointState {
  static constexpr std::uint32_t layout_version = 1;
  static constexpr std::size_t max_joints = 8;
  std::uint32_t size = 0;
  std::array<double, max_joints> position{};
  std::array<double, max_joints> velocity{};
  std::array<double, max_joints> effort{};
};

// crtk_msgs/OperatingState.
enum class OperatingStateValue : std::uint8_t { disabled, enabled, paused, fault };

struct OperatingState {
  static constexpr std::uint32_t layout_version = 1;
  OperatingStateValue state = OperatingStateValue::disabled;
  bool is_homed = false;
  bool is_busy = false;
};

// The CRTK state_command strings, as an enum for RT code.
enum class StateCommand : std::uint8_t { enable, disable, pause, resume, home };

constexpr std::string_view to_string(OperatingStateValue s) {
  switch (s) {
    case OperatingStateValue::disabled:
      return "DISABLED";
    case OperatingStateValue::enabled:
      return "ENABLED";
    case OperatingStateValue::paused:
      return "PAUSED";
    case OperatingStateValue::fault:
      return "FAULT";
  }
  return "?";
}

constexpr std::string_view to_string(StateCommand c) {
  switch (c) {
    case StateCommand::enable:
      return "enable";
    case StateCommand::disable:
      return "disable";
    case StateCommand::pause:
      return "pause";
    case StateCommand::resume:
      return "resume";
    case StateCommand::home:
      return "home";
  }
  return "?";
}

// Button events (sensor_msgs/Joy-like): pressed or released.
struct ButtonEvent {
  static constexpr std::uint32_t layout_version = 1;
  bool pressed = false;
};

}  // namespace saw
