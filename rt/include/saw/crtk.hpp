// CRTK value types (poses, twists, wrenches, joint states, operating states) as Plain structs.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <tuple>

namespace saw {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // x, y, z, w (ROS order)

// Every type here crosses processes byte for byte (the bridge, the gateway): the asserts below
// each type turn an accidental change of its layout into a compile error. A deliberate change
// bumps its layout_version and the asserts with it.

// geometry_msgs/Pose; the stamp is the state-table row's.
struct Pose {
  static constexpr std::string_view type_name = "saw::Pose";
  static constexpr std::uint32_t layout_version = 1;
  Vec3 position{};
  Quat orientation{0, 0, 0, 1};
  static constexpr auto fields = std::tuple{&Pose::position, &Pose::orientation};
  static bool valid(const Pose& p) noexcept {  // a unit quaternion, as the gateway requires
    const auto& q = p.orientation;
    return std::abs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1.0) <= 2e-3;
  }
};
static_assert(sizeof(Pose) == 56 && offsetof(Pose, orientation) == 24);

// geometry_msgs/Twist.
struct Twist {
  static constexpr std::string_view type_name = "saw::Twist";
  static constexpr std::uint32_t layout_version = 1;
  Vec3 linear{};
  Vec3 angular{};
  static constexpr auto fields = std::tuple{&Twist::linear, &Twist::angular};
};
static_assert(sizeof(Twist) == 48 && offsetof(Twist, angular) == 24);

// geometry_msgs/Wrench.
struct Wrench {
  static constexpr std::string_view type_name = "saw::Wrench";
  static constexpr std::uint32_t layout_version = 1;
  Vec3 force{};
  Vec3 torque{};
  static constexpr auto fields = std::tuple{&Wrench::force, &Wrench::torque};
};
static_assert(sizeof(Wrench) == 48 && offsetof(Wrench, torque) == 24);

// sensor_msgs/JointState with a fixed maximum size (a da Vinci MTM has 7 joints + gripper).
// The joints' names travel in every value, as in sensor_msgs/JointState (whose `name` is empty
// or as long as `position`): a separate read-once command would spare the device copying 256
// bytes more per cycle (tens of ns), but leave every consumer (the gateway, a recorder, a proxy
// in another process) to pair names with positions itself, and to notice when they change.
struct JointState {
  static constexpr std::string_view type_name = "saw::JointState";
  static constexpr std::uint32_t layout_version = 2;  // 2: joint names
  static constexpr std::size_t max_joints = 8;
  static constexpr std::size_t max_name = 31;  // characters, then at least one NUL
  using Name = std::array<char, max_name + 1>;
  std::uint32_t size = 0;
  std::array<double, max_joints> position{};
  std::array<double, max_joints> velocity{};
  std::array<double, max_joints> effort{};
  std::array<Name, max_joints> name{};  // the first `size` all named, or none (then all empty)
  static constexpr auto fields = std::tuple{&JointState::size, &JointState::position, &JointState::velocity,
                                            &JointState::effort, &JointState::name};

  // Joint i's name; "" when unnamed or out of range.
  constexpr std::string_view name_of(std::size_t i) const noexcept {
    if (i >= max_joints) return {};
    std::size_t n = 0;
    while (n < name[i].size() && name[i][n] != '\0') ++n;
    return {name[i].data(), n};
  }
  // False, changing nothing, when i is out of range or `n` too long or holds a NUL.
  constexpr bool set_name(std::size_t i, std::string_view n) noexcept {
    if (i >= max_joints || n.size() > max_name || n.find('\0') != std::string_view::npos) return false;
    name[i] = {};
    for (std::size_t k = 0; k < n.size(); ++k) name[i][k] = n[k];
    return true;
  }
  constexpr bool named() const noexcept { return size > 0 && name[0][0] != '\0'; }
  static constexpr bool valid(const JointState& j) noexcept {
    if (j.size > max_joints) return false;
    for (std::size_t i = 0; i < max_joints; ++i) {
      if (j.name[i][max_name] != '\0') return false;  // terminated inside its field
      const bool has_name = j.name[i][0] != '\0';
      if (has_name != (i < j.size && j.named())) return false;
    }
    return true;
  }
};
static_assert(sizeof(JointState) == 456 && offsetof(JointState, position) == 8 &&
              offsetof(JointState, velocity) == 72 && offsetof(JointState, effort) == 136 &&
              offsetof(JointState, name) == 200);

// crtk_msgs/OperatingState.
enum class OperatingStateValue : std::uint8_t { disabled, enabled, paused, fault };
constexpr std::size_t enum_count(OperatingStateValue) { return 4; }
constexpr std::string_view enum_type_name(OperatingStateValue) { return "saw::OperatingStateValue"; }

struct OperatingState {
  static constexpr std::string_view type_name = "saw::OperatingState";
  static constexpr std::uint32_t layout_version = 1;
  OperatingStateValue state = OperatingStateValue::disabled;
  bool is_homed = false;
  bool is_busy = false;
  static constexpr auto fields =
      std::tuple{&OperatingState::state, &OperatingState::is_homed, &OperatingState::is_busy};
};
static_assert(sizeof(OperatingState) == 3 && offsetof(OperatingState, is_homed) == 1 &&
              offsetof(OperatingState, is_busy) == 2);

// The CRTK state_command strings, as an enum for RT code.
enum class StateCommand : std::uint8_t { enable, disable, pause, resume, home };
constexpr std::size_t enum_count(StateCommand) { return 5; }
constexpr std::string_view enum_type_name(StateCommand) { return "saw::StateCommand"; }
static_assert(sizeof(StateCommand) == 1);

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
  static constexpr std::string_view type_name = "saw::ButtonEvent";
  static constexpr std::uint32_t layout_version = 1;
  bool pressed = false;
  static constexpr auto fields = std::tuple{&ButtonEvent::pressed};
};
static_assert(sizeof(ButtonEvent) == 1);

}  // namespace saw
