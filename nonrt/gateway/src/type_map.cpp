#include "saw/gateway/type_map.hpp"

#include <fastcdr/exceptions/Exception.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <iterator>
#include <memory>
#include <sstream>
#include <vector>

#include "crtk_msgs/msg/OperatingStatePubSubTypes.h"
#include "crtk_msgs/msg/StringStampedPubSubTypes.h"
#include "geometry_msgs/msg/PoseStampedPubSubTypes.h"
#include "geometry_msgs/msg/TwistStampedPubSubTypes.h"
#include "geometry_msgs/msg/Vector3StampedPubSubTypes.h"
#include "geometry_msgs/msg/WrenchStampedPubSubTypes.h"
#include "saw/crtk.hpp"
#include "saw/fault.hpp"
#include "saw/task.hpp"
#include "saw/teleop/teleop_law.hpp"
#include "saw/type_info.hpp"
#include "saw_msgs/msg/MasterSlavePubSubTypes.h"
#include "saw_msgs/msg/TaskStatisticsPubSubTypes.h"
#include "sensor_msgs/msg/JointStatePubSubTypes.h"
#include "sensor_msgs/msg/JoyPubSubTypes.h"
#include "std_msgs/msg/BoolPubSubTypes.h"
#include "std_msgs/msg/EmptyPubSubTypes.h"
#include "std_msgs/msg/Float64PubSubTypes.h"
#include "std_msgs/msg/Int64PubSubTypes.h"

namespace saw::gateway {

namespace fdds = eprosima::fastdds::dds;

namespace {

// The next valid sample into `m`: false when there is none. A peer's sample that Fast CDR cannot
// read (a bad encapsulation) throws from the generated deserializer inside take_next_sample: it
// is refused here, with the reason, instead of ending the gateway's thread (fuzz: gateway_sample).
template <class Msg>
ReturnCode_t take_next(fdds::DataReader& r, Msg& m, std::string& why) {
  fdds::SampleInfo info;
  for (;;) {
    try {
      const ReturnCode_t rc = r.take_next_sample(&m, &info);
      if (rc != ReturnCode_t::RETCODE_OK || info.valid_data) return rc;  // skip disposal notices
    } catch (const eprosima::fastcdr::exception::Exception& e) {
      why = std::string("malformed sample: ") + e.what();
      return ReturnCode_t::RETCODE_ERROR;
    }
  }
}

bool finite(std::initializer_list<double> xs) {
  for (double x : xs)
    if (!std::isfinite(x)) return false;
  return true;
}

template <class V>
void put(const Vec3& a, V& v) {
  v.x(a[0]);
  v.y(a[1]);
  v.z(a[2]);
}
template <class V>
bool get(const V& v, Vec3& a, std::string& why, const char* what) {
  a = {v.x(), v.y(), v.z()};
  if (finite({a[0], a[1], a[2]})) return true;
  why = std::string(what) + " is not finite";
  return false;
}
// Whitespace- or comma-separated numbers.
std::vector<double> numbers(std::string_view t, std::string& why) {
  std::vector<double> v;
  std::string s(t);
  for (char& c : s)
    if (c == ',' || c == '[' || c == ']') c = ' ';
  std::istringstream in(s);
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    const double x = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') {
      why = "\"" + word + "\" is not a number";
      return {};
    }
    v.push_back(x);
  }
  return v;
}

bool count_is(const std::vector<double>& v, std::initializer_list<std::size_t> ok, std::string& why) {
  for (auto n : ok)
    if (v.size() == n) return true;
  if (why.empty()) {
    why = "expected ";
    for (auto n : ok) why += std::to_string(n) + (n == *std::prev(ok.end()) ? "" : " or ");
    why += " numbers, got " + std::to_string(v.size());
  }
  return false;
}

std::string trimmed(std::string_view t) {
  const auto b = t.find_first_not_of(" \t\n");
  if (b == std::string_view::npos) return "";
  return std::string(t.substr(b, t.find_last_not_of(" \t\n") - b + 1));
}

std::string text(const Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "[%.6g, %.6g, %.6g]", v[0], v[1], v[2]);
  return b;
}

// One rt type Rt carried as message Msg; Conv supplies to_msg / from_msg / to_text.
template <class Rt, class Msg, class PubSub, class Conv>
class Typed final : public Mapping {
 public:
  std::string_view saw_type() const override { return type_info_of<Rt>().name; }
  std::uint32_t saw_version() const override { return type_info_of<Rt>().version; }
  std::string_view dds_type() const override { return name_; }
  fdds::TypeSupport type_support() const override { return fdds::TypeSupport(new PubSub()); }
  std::size_t size() const override { return sizeof(Rt); }

  bool write(fdds::DataWriter& w, const void* value, std::int64_t stamp_ns,
             std::string_view frame) const override {
    Msg m;
    if constexpr (requires { m.header(); }) {
      m.header().stamp().sec(static_cast<std::int32_t>(stamp_ns / 1'000'000'000));
      m.header().stamp().nanosec(static_cast<std::uint32_t>(stamp_ns % 1'000'000'000));
      m.header().frame_id(std::string(frame));
    }
    Conv::to_msg(*static_cast<const Rt*>(value), m);
    return w.write(&m);
  }

  Take take(fdds::DataReader& r, void* value, std::string& why) const override {
    Msg m;
    why.clear();
    if (const ReturnCode_t rc = take_next(r, m, why); rc != ReturnCode_t::RETCODE_OK)
      return why.empty() ? Take::none : Take::rejected;
    Rt v{};
    if (!Conv::from_msg(m, v, why)) return Take::rejected;
    *static_cast<Rt*>(value) = v;
    return Take::ok;
  }

  std::string to_text(const void* value) const override { return Conv::text(*static_cast<const Rt*>(value)); }
  void numbers(const void* value, std::vector<double>& out) const override {
    if constexpr (requires(const Rt& r, std::vector<double>& o) { Conv::each(r, o); })
      Conv::each(*static_cast<const Rt*>(value), out);
  }
  bool check(const void* value, const Limits& limits) const override {
    return saw::check_value(*static_cast<const Rt*>(value), &limits);
  }

  bool from_text(std::string_view text, void* value, std::string& why) const override {
    Rt v{};
    if (!Conv::parse(text, v, why)) return false;
    // Through the message and back: the same validation as a sample arriving from DDS.
    Msg m;
    Conv::to_msg(v, m);
    Rt checked{};
    if (!Conv::from_msg(m, checked, why)) return false;
    *static_cast<Rt*>(value) = checked;
    return true;
  }

 private:
  std::string name_ = PubSub().getName();
};

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
    return "p " + saw::gateway::text(p.position) + b;
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
    return "v " + saw::gateway::text(t.linear) + " w " + saw::gateway::text(t.angular);
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
    return "f " + saw::gateway::text(w.force) + " t " + saw::gateway::text(w.torque);
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
  static std::string text(const Vec3& v) { return saw::gateway::text(v); }
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

// Buttons as the dVRK publishes them: sensor_msgs/Joy with buttons[0] = 1 pressed, 0 released.
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
    b.pressed = m.buttons()[0] != 0;
    return true;
  }
  static std::string text(const ButtonEvent& b) { return b.pressed ? "pressed" : "released"; }
};

template <class T, class Msg>
struct DataConv {
  static void each(const T& v, std::vector<double>& o) {
    if constexpr (!std::is_same_v<T, bool>) o.push_back(static_cast<double>(v));
  }
  static void to_msg(const T& v, Msg& m) { m.data(v); }
  static bool from_msg(const Msg& m, T& v, std::string& why) {
    v = m.data();
    if constexpr (std::is_floating_point_v<T>)
      if (!std::isfinite(v)) {
        why = "value is not finite";
        return false;
      }
    return true;
  }
  static std::string text(const T& v) { return std::to_string(v); }
  static bool parse(std::string_view t, T& v, std::string& why) {
    const auto w = trimmed(t);
    if constexpr (std::is_same_v<T, bool>) {
      if (w != "true" && w != "false") {
        why = "\"" + w + "\": true or false";
        return false;
      }
      v = w == "true";
      return true;
    } else {
      const auto n = numbers(w, why);
      if (!count_is(n, {1}, why)) return false;
      if constexpr (std::is_integral_v<T>) {
        if (n[0] != std::floor(n[0]) || std::abs(n[0]) > 9.0e15) {
          why = "\"" + w + "\" is not an integer";
          return false;
        }
      }
      v = static_cast<T>(n[0]);
      return true;
    }
  }
};

class EmptyMapping final : public Mapping {
 public:
  std::string_view saw_type() const override { return ""; }
  std::uint32_t saw_version() const override { return 0; }
  std::string_view dds_type() const override { return name_; }
  fdds::TypeSupport type_support() const override {
    return fdds::TypeSupport(new std_msgs::msg::EmptyPubSubType());
  }
  std::size_t size() const override { return 0; }
  bool write(fdds::DataWriter& w, const void*, std::int64_t, std::string_view) const override {
    std_msgs::msg::Empty m;
    return w.write(&m);
  }
  Take take(fdds::DataReader& r, void*, std::string& why) const override {
    std_msgs::msg::Empty m;
    why.clear();
    if (take_next(r, m, why) == ReturnCode_t::RETCODE_OK) return Take::ok;
    return why.empty() ? Take::none : Take::rejected;
  }
  std::string to_text(const void*) const override { return "(void)"; }
  bool from_text(std::string_view text, void*, std::string& why) const override {
    if (trimmed(text).empty()) return true;
    why = "a void command takes no value";
    return false;
  }

 private:
  std::string name_ = std_msgs::msg::EmptyPubSubType().getName();
};

// A teleoperation setting with one number per side (teleop::Gains, teleop::ForceLimits), as
// saw_msgs/MasterSlave; text "MASTER SLAVE".
template <class T>
struct MasterSlaveConv {
  static void each(const T& v, std::vector<double>& o) { o.insert(o.end(), {v.master, v.slave}); }
  static void to_msg(const T& v, saw_msgs::msg::MasterSlave& m) {
    m.master(v.master);
    m.slave(v.slave);
  }
  static bool from_msg(const saw_msgs::msg::MasterSlave& m, T& v, std::string& why) {
    if (!std::isfinite(m.master()) || !std::isfinite(m.slave())) {
      why = "master or slave is not finite";
      return false;
    }
    v.master = m.master();
    v.slave = m.slave();
    return true;
  }
  static std::string text(const T& v) {
    char b[64];
    std::snprintf(b, sizeof b, "master %.6g slave %.6g", v.master, v.slave);
    return b;
  }
  static bool parse(std::string_view t, T& v, std::string& why) {
    const auto n = numbers(t, why);
    if (!count_is(n, {2}, why)) return false;
    v.master = n[0];
    v.slave = n[1];
    return true;
  }
};

// A task's period_statistics, as saw_msgs/TaskStatistics (read-only: never a command).
struct TaskStatisticsConv {
  static void to_msg(const TaskStatistics& v, saw_msgs::msg::TaskStatistics& m) {
    m.cycles(v.cycles);
    m.overruns(v.overruns);
    m.missed_periods(v.missed_periods);
    m.period(v.period);
    m.last_wakeup_latency(v.last_wakeup_latency);
    m.max_wakeup_latency(v.max_wakeup_latency);
    m.last_compute(v.last_compute);
    m.max_compute(v.max_compute);
    m.mean_compute(v.mean_compute);
  }
  static bool from_msg(const saw_msgs::msg::TaskStatistics& m, TaskStatistics& v, std::string& why) {
    if (!std::isfinite(m.mean_compute())) {
      why = "mean_compute is not finite";
      return false;
    }
    v.cycles = m.cycles();
    v.overruns = m.overruns();
    v.missed_periods = m.missed_periods();
    v.period = m.period();
    v.last_wakeup_latency = m.last_wakeup_latency();
    v.max_wakeup_latency = m.max_wakeup_latency();
    v.last_compute = m.last_compute();
    v.max_compute = m.max_compute();
    v.mean_compute = m.mean_compute();
    return true;
  }
  static std::string text(const TaskStatistics& v) {
    char b[200];
    std::snprintf(
        b, sizeof b,
        "cycles %llu overruns %llu missed %llu wake-up %.1f us (max %.1f) compute %.1f us (max %.1f)",
        static_cast<unsigned long long>(v.cycles), static_cast<unsigned long long>(v.overruns),
        static_cast<unsigned long long>(v.missed_periods), static_cast<double>(v.last_wakeup_latency) / 1e3,
        static_cast<double>(v.max_wakeup_latency) / 1e3, static_cast<double>(v.last_compute) / 1e3,
        static_cast<double>(v.max_compute) / 1e3);
    return b;
  }
  static bool parse(std::string_view, TaskStatistics&, std::string& why) {
    why = "task statistics are read, not sent";
    return false;
  }
};

const std::vector<std::unique_ptr<Mapping>>& mappings() {
  static const auto all = [] {
    std::vector<std::unique_ptr<Mapping>> v;
    using namespace geometry_msgs::msg;
    v.push_back(std::make_unique<Typed<Pose, PoseStamped, PoseStampedPubSubType, PoseConv>>());
    v.push_back(std::make_unique<Typed<Twist, TwistStamped, TwistStampedPubSubType, TwistConv>>());
    v.push_back(std::make_unique<Typed<Wrench, WrenchStamped, WrenchStampedPubSubType, WrenchConv>>());
    v.push_back(std::make_unique<Typed<Vec3, Vector3Stamped, Vector3StampedPubSubType, Vec3Conv>>());
    v.push_back(std::make_unique<Typed<JointState, sensor_msgs::msg::JointState,
                                       sensor_msgs::msg::JointStatePubSubType, JointStateConv>>());
    v.push_back(std::make_unique<Typed<OperatingState, crtk_msgs::msg::OperatingState,
                                       crtk_msgs::msg::OperatingStatePubSubType, OperatingStateConv>>());
    v.push_back(std::make_unique<Typed<StateCommand, crtk_msgs::msg::StringStamped,
                                       crtk_msgs::msg::StringStampedPubSubType, StateCommandConv>>());
    // After StateCommand: a lookup by DDS type (StringStamped) still finds the state command.
    v.push_back(std::make_unique<Typed<FaultInfo, crtk_msgs::msg::StringStamped,
                                       crtk_msgs::msg::StringStampedPubSubType, FaultInfoConv>>());
    v.push_back(std::make_unique<
                Typed<ButtonEvent, sensor_msgs::msg::Joy, sensor_msgs::msg::JoyPubSubType, ButtonConv>>());
    v.push_back(std::make_unique<Typed<double, std_msgs::msg::Float64, std_msgs::msg::Float64PubSubType,
                                       DataConv<double, std_msgs::msg::Float64>>>());
    v.push_back(std::make_unique<Typed<std::int64_t, std_msgs::msg::Int64, std_msgs::msg::Int64PubSubType,
                                       DataConv<std::int64_t, std_msgs::msg::Int64>>>());
    v.push_back(std::make_unique<Typed<bool, std_msgs::msg::Bool, std_msgs::msg::BoolPubSubType,
                                       DataConv<bool, std_msgs::msg::Bool>>>());
    // Both on one message type: a lookup by DDS type finds Gains, whose layout ForceLimits shares
    // (two doubles, master then slave), so the bytes are the same either way.
    using saw_msgs::msg::MasterSlave, saw_msgs::msg::MasterSlavePubSubType;
    v.push_back(std::make_unique<
                Typed<teleop::Gains, MasterSlave, MasterSlavePubSubType, MasterSlaveConv<teleop::Gains>>>());
    v.push_back(std::make_unique<Typed<teleop::ForceLimits, MasterSlave, MasterSlavePubSubType,
                                       MasterSlaveConv<teleop::ForceLimits>>>());
    v.push_back(std::make_unique<Typed<TaskStatistics, saw_msgs::msg::TaskStatistics,
                                       saw_msgs::msg::TaskStatisticsPubSubType, TaskStatisticsConv>>());
    return v;
  }();
  return all;
}

}  // namespace

bool within_limits(const Mapping& m, const void* value, const Limits& limits, std::string& why) {
  if (m.check(value, limits)) return true;
  std::vector<double> shown;
  m.numbers(value, shown);
  char b[160];
  const auto outside = std::find_if(shown.begin(), shown.end(),
                                    [&](double x) { return !(x >= limits.min && x <= limits.max); });
  if (outside != shown.end())
    std::snprintf(b, sizeof b, "%g is outside [%g, %g], the range the component declares", *outside,
                  limits.min, limits.max);
  else
    std::snprintf(b, sizeof b, "a number of the value is outside [%g, %g], the range the component declares",
                  limits.min, limits.max);
  why = b;
  return false;
}

const Mapping* find_mapping(std::string_view saw_type) {
  for (const auto& m : mappings())
    if (m->saw_type() == saw_type) return m.get();
  return nullptr;
}

const Mapping* find_mapping_by_dds(std::string_view dds_type) {
  for (const auto& m : mappings())
    if (m->dds_type() == dds_type) return m.get();
  if (dds_type == empty_mapping().dds_type()) return &empty_mapping();
  return nullptr;
}

const Mapping& empty_mapping() {
  static const EmptyMapping m;
  return m;
}

std::int64_t wall_from_monotonic(TimeNs monotonic) {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  const std::int64_t wall = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  return wall - (monotonic_now() - monotonic);
}

}  // namespace saw::gateway
