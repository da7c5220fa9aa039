// The conversions of the CRTK value types (poses, twists, wrenches, joints, states, commands,
// buttons, faults) to and from their ROS 2 / CRTK messages.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "crtk_msgs/msg/OperatingState.h"
#include "crtk_msgs/msg/StringStamped.h"
#include "geometry_msgs/msg/PoseStamped.h"
#include "geometry_msgs/msg/TwistStamped.h"
#include "geometry_msgs/msg/Vector3Stamped.h"
#include "geometry_msgs/msg/WrenchStamped.h"
#include "saw/crtk.hpp"
#include "saw/fault.hpp"
#include "saw/gateway/typed_mapping.hpp"
#include "sensor_msgs/msg/JointState.h"
#include "sensor_msgs/msg/Joy.h"

namespace saw::gateway::conversions {

using namespace convert;

struct PoseConv {
  static void each(const Pose& p, std::vector<double>& o) {
    o.insert(o.end(), p.position.begin(), p.position.end());
  }
  static bool parse(std::string_view t, Pose& p, std::string& why) {
    const auto v = numbers(t, why);
    if (!count_is(v, {3, 7}, why)) return false;
    p.position = {v[0], v[1], v[2]};
    if (v.size() == 7) p.orientation = {v[3], v[4], v[5], v[6]};
    return true;
  }

  static void to_msg(const Pose& p, geometry_msgs::msg::PoseStamped& m) {
    put(p.position, m.pose().position());
    auto& q = m.pose().orientation();
    q.x(p.orientation[0]);
    q.y(p.orientation[1]);
    q.z(p.orientation[2]);
    q.w(p.orientation[3]);
  }
  static bool from_msg(const geometry_msgs::msg::PoseStamped& m, Pose& p, std::string& why) {
    if (!get(m.pose().position(), p.position, why, "position")) return false;
    const auto& q = m.pose().orientation();
    p.orientation = {q.x(), q.y(), q.z(), q.w()};
    const double n = std::sqrt(q.x() * q.x() + q.y() * q.y() + q.z() * q.z() + q.w() * q.w());
    if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3) {
      why = "orientation is not a unit quaternion (norm " + std::to_string(n) + ")";
      return false;
    }
    return true;
  }
  static std::string text(const Pose& p) {
    char b[96];
    std::snprintf(b, sizeof b, " q [%.4f, %.4f, %.4f, %.4f]", p.orientation[0], p.orientation[1],
                  p.orientation[2], p.orientation[3]);
    return "p " + convert::text(p.position) + b;
  }
};

struct TwistConv {
  static void each(const Twist& t, std::vector<double>& o) {
    o.insert(o.end(), t.linear.begin(), t.linear.end());
    o.insert(o.end(), t.angular.begin(), t.angular.end());
  }
  static bool parse(std::string_view t, Twist& w, std::string& why) {
    const auto v = numbers(t, why);
    if (!count_is(v, {3, 6}, why)) return false;
    w.linear = {v[0], v[1], v[2]};
    if (v.size() == 6) w.angular = {v[3], v[4], v[5]};
    return true;
  }

  static void to_msg(const Twist& t, geometry_msgs::msg::TwistStamped& m) {
    put(t.linear, m.twist().linear());
    put(t.angular, m.twist().angular());
  }
  static bool from_msg(const geometry_msgs::msg::TwistStamped& m, Twist& t, std::string& why) {
    return get(m.twist().linear(), t.linear, why, "linear") &&
           get(m.twist().angular(), t.angular, why, "angular");
  }
  static std::string text(const Twist& t) {
    return "v " + convert::text(t.linear) + " w " + convert::text(t.angular);
  }
};

struct WrenchConv {
  static void each(const Wrench& w, std::vector<double>& o) {
    o.insert(o.end(), w.force.begin(), w.force.end());
    o.insert(o.end(), w.torque.begin(), w.torque.end());
  }
  static bool parse(std::string_view t, Wrench& w, std::string& why) {
    const auto v = numbers(t, why);
    if (!count_is(v, {3, 6}, why)) return false;
    w.force = {v[0], v[1], v[2]};
    if (v.size() == 6) w.torque = {v[3], v[4], v[5]};
    return true;
  }

  static void to_msg(const Wrench& w, geometry_msgs::msg::WrenchStamped& m) {
    put(w.force, m.wrench().force());
    put(w.torque, m.wrench().torque());
  }
  static bool from_msg(const geometry_msgs::msg::WrenchStamped& m, Wrench& w, std::string& why) {
    return get(m.wrench().force(), w.force, why, "force") &&
           get(m.wrench().torque(), w.torque, why, "torque");
  }
  static std::string text(const Wrench& w) {
    return "f " + convert::text(w.force) + " t " + convert::text(w.torque);
  }
};

struct Vec3Conv {
  static void each(const Vec3& v, std::vector<double>& o) { o.insert(o.end(), v.begin(), v.end()); }
  static bool parse(std::string_view t, Vec3& a, std::string& why) {
    const auto v = numbers(t, why);
    if (!count_is(v, {3}, why)) return false;
    a = {v[0], v[1], v[2]};
    return true;
  }

  static void to_msg(const Vec3& v, geometry_msgs::msg::Vector3Stamped& m) { put(v, m.vector()); }
  static bool from_msg(const geometry_msgs::msg::Vector3Stamped& m, Vec3& v, std::string& why) {
    return get(m.vector(), v, why, "vector");
  }
  static std::string text(const Vec3& v) { return convert::text(v); }
};

struct JointStateConv {
  static void each(const JointState& j, std::vector<double>& o) {
    for (std::uint32_t i = 0; i < j.size && i < JointState::max_joints; ++i) {
      o.push_back(j.position[i]);
      o.push_back(j.velocity[i]);
      o.push_back(j.effort[i]);
    }
  }
  static bool parse(std::string_view t, JointState& j, std::string& why) {
    const auto v = numbers(t, why);
    if (!why.empty()) return false;
    if (v.empty() || v.size() > JointState::max_joints) {
      why = "1 to " + std::to_string(JointState::max_joints) + " joint positions, got " +
            std::to_string(v.size());
      return false;
    }
    j.size = static_cast<std::uint32_t>(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) j.position[i] = v[i];
    return true;
  }

  static void to_msg(const JointState& j, sensor_msgs::msg::JointState& m) {
    const auto n = std::min<std::size_t>(j.size, JointState::max_joints);
    // ROS tools (robot_state_publisher, rviz) pair positions with joints by name.
    m.name().clear();
    if (j.named())
      for (std::size_t i = 0; i < n; ++i) m.name().emplace_back(j.name_of(i));
    m.position().assign(j.position.begin(), j.position.begin() + static_cast<std::ptrdiff_t>(n));
    m.velocity().assign(j.velocity.begin(), j.velocity.begin() + static_cast<std::ptrdiff_t>(n));
    m.effort().assign(j.effort.begin(), j.effort.begin() + static_cast<std::ptrdiff_t>(n));
  }
  static bool from_msg(const sensor_msgs::msg::JointState& m, JointState& j, std::string& why) {
    const std::size_t n = m.position().size();
    if (n > JointState::max_joints) {
      why = std::to_string(n) + " joints, at most " + std::to_string(JointState::max_joints);
      return false;
    }
    for (const auto* s : {&m.velocity(), &m.effort()})
      if (!s->empty() && s->size() != n) {
        why = "velocity/effort sizes differ from position's (" + std::to_string(n) + ")";
        return false;
      }
    if (!m.name().empty() && m.name().size() != n) {
      why = std::to_string(m.name().size()) + " names for " + std::to_string(n) + " joints";
      return false;
    }
    j.size = static_cast<std::uint32_t>(n);
    j.name = {};
    for (std::size_t i = 0; i < m.name().size(); ++i)
      if (m.name()[i].empty() || !j.set_name(i, m.name()[i])) {
        why = "joint " + std::to_string(i) + "'s name \"" + m.name()[i] + "\" is empty or longer than " +
              std::to_string(JointState::max_name) + " characters";
        return false;
      }
    for (std::size_t i = 0; i < n; ++i) {
      j.position[i] = m.position()[i];
      j.velocity[i] = m.velocity().empty() ? 0.0 : m.velocity()[i];
      j.effort[i] = m.effort().empty() ? 0.0 : m.effort()[i];
      if (!finite({j.position[i], j.velocity[i], j.effort[i]})) {
        why = "joint " + std::to_string(i) + " is not finite";
        return false;
      }
    }
    return true;
  }
  static std::string text(const JointState& j) {
    std::string s;
    if (j.named()) {
      s = "name [";
      for (std::uint32_t i = 0; i < std::min<std::uint32_t>(j.size, JointState::max_joints); ++i)
        s += (i ? ", " : "") + std::string(j.name_of(i));
      s += "] ";
    }
    s += "position [";
    for (std::uint32_t i = 0; i < std::min<std::uint32_t>(j.size, JointState::max_joints); ++i)
      s += (i ? ", " : "") + std::to_string(j.position[i]);
    return s + "]";
  }
};

struct OperatingStateConv {
  static bool parse(std::string_view t, OperatingState& s, std::string& why) {
    crtk_msgs::msg::OperatingState m;
    m.state(trimmed(t));
    return from_msg(m, s, why);
  }

  static void to_msg(const OperatingState& s, crtk_msgs::msg::OperatingState& m) {
    m.state(std::string(to_string(s.state)));
    m.is_homed(s.is_homed);
    m.is_busy(s.is_busy);
  }
  static bool from_msg(const crtk_msgs::msg::OperatingState& m, OperatingState& s, std::string& why) {
    for (auto v : {OperatingStateValue::disabled, OperatingStateValue::enabled, OperatingStateValue::paused,
                   OperatingStateValue::fault})
      if (m.state() == to_string(v)) {
        s.state = v;
        s.is_homed = m.is_homed();
        s.is_busy = m.is_busy();
        return true;
      }
    why = "unknown operating state \"" + m.state() + "\"";
    return false;
  }
  static std::string text(const OperatingState& s) {
    return std::string(to_string(s.state)) + (s.is_homed ? " homed" : " not homed") +
           (s.is_busy ? " busy" : "");
  }
};

struct StateCommandConv {
  static bool parse(std::string_view t, StateCommand& c, std::string& why) {
    crtk_msgs::msg::StringStamped m;
    m.string(trimmed(t));
    return from_msg(m, c, why);
  }

  static void to_msg(const StateCommand& c, crtk_msgs::msg::StringStamped& m) {
    m.string(std::string(to_string(c)));
  }
  static bool from_msg(const crtk_msgs::msg::StringStamped& m, StateCommand& c, std::string& why) {
    for (auto v : {StateCommand::enable, StateCommand::disable, StateCommand::pause, StateCommand::resume,
                   StateCommand::home})
      if (m.string() == to_string(v)) {
        c = v;
        return true;
      }
    why = "unknown state command \"" + m.string() + "\" (enable, disable, pause, resume, home)";
    return false;
  }
  static std::string text(const StateCommand& c) { return std::string(to_string(c)); }
};

// Why a component (the teleoperation task, a driver) FAULTed, for people and GUIs: one line of text (its
// to_string), "master input stale: 23.4 ms old (last read: disconnected), at t=4.512 s". Published only: the
// text is not parsed back (a mirror skips the endpoint, as for any type it cannot decode).
struct FaultInfoConv {
  static void to_msg(const FaultInfo& f, crtk_msgs::msg::StringStamped& m) { m.string(to_string(f)); }
  static bool from_msg(const crtk_msgs::msg::StringStamped&, FaultInfo&, std::string& why) {
    why = "a fault is published as text only";
    return false;
  }
  static bool parse(std::string_view, FaultInfo&, std::string& why) {
    why = "a fault is published as text only";
    return false;
  }
  static std::string text(const FaultInfo& f) { return to_string(f); }
};

// Buttons as the dVRK publishes them: sensor_msgs/Joy with buttons[0] = 1 pressed, 0 released,
// 2 a quick tap (cisst-ros's CLICKED, sent beside the press and release): not a state of the
// button, so no event (taken as pressed it would leave a clutch held that the operator let go).
struct ButtonConv {
  static bool parse(std::string_view t, ButtonEvent& b, std::string& why) {
    const auto w = trimmed(t);
    if (w == "pressed" || w == "1" || w == "true")
      b.pressed = true;
    else if (w == "released" || w == "0" || w == "false")
      b.pressed = false;
    else {
      why = "\"" + w + "\": pressed or released";
      return false;
    }
    return true;
  }

  static void to_msg(const ButtonEvent& b, sensor_msgs::msg::Joy& m) { m.buttons({b.pressed ? 1 : 0}); }
  static bool from_msg(const sensor_msgs::msg::Joy& m, ButtonEvent& b, std::string& why) {
    if (m.buttons().empty()) {
      why = "no button in the message";
      return false;
    }
    if (m.buttons()[0] != 0 && m.buttons()[0] != 1) {
      why = "buttons[0] " + std::to_string(m.buttons()[0]) +
            ": 1 pressed, 0 released (2, a quick tap, is neither)";
      return false;
    }
    b.pressed = m.buttons()[0] == 1;
    return true;
  }
  static std::string text(const ButtonEvent& b) { return b.pressed ? "pressed" : "released"; }
};

}  // namespace saw::gateway::conversions
