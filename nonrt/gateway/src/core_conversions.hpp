// The conversions of the rt core's other types: plain numbers and booleans (std_msgs), a task's
// period statistics and a component's description (saw_msgs).
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "saw/description.hpp"
#include "saw/gateway/typed_mapping.hpp"
#include "saw/task.hpp"
#include "saw_msgs/msg/ComponentDescription.h"
#include "saw_msgs/msg/TaskStatistics.h"

namespace saw::gateway::conversions {

using namespace convert;

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

// What a component is, as saw_msgs/ComponentDescription (read-only: never a command). Roles
// are sent up to the first empty one; a peer's text longer than the field holds is refused, not
// cut.
struct DescriptionConv {
  using D = ComponentDescription;
  static void to_msg(const D& d, saw_msgs::msg::ComponentDescription& m) {
    m.kind(std::string(D::get(d.kind)));
    m.variant(std::string(D::get(d.variant)));
    m.roles().clear();
    m.servers().clear();
    for (std::size_t i = 0; i < D::max_roles && !D::get(d.roles[i]).empty(); ++i) {
      m.roles().emplace_back(D::get(d.roles[i]));
      m.servers().emplace_back(D::get(d.servers[i]));
    }
    m.settings().clear();
    for (std::size_t i = 0; i < d.setting_count && i < D::max_settings; ++i) {
      const DeclaredSetting& s = d.settings[i];
      saw_msgs::msg::DeclaredSetting out;
      out.name(std::string(D::get(s.name)));
      out.unit(std::string(D::get(s.unit)));
      out.min(s.min);
      out.max(s.max);
      out.count(s.count);
      out.command(s.command);
      m.settings().push_back(out);
    }
  }
  template <std::size_t N>
  static bool fits(std::array<char, N>& field, const std::string& text, const char* what, std::string& why) {
    if (text.size() >= N || text.find('\0') != std::string::npos) {
      why = std::string(what) + " \"" + text.substr(0, 40) + "\" is longer than " + std::to_string(N - 1) +
            " characters";
      return false;
    }
    D::set(field, text);
    return true;
  }
  static bool from_msg(const saw_msgs::msg::ComponentDescription& m, D& d, std::string& why) {
    if (m.roles().size() > D::max_roles || m.servers().size() != m.roles().size()) {
      why = std::to_string(m.roles().size()) + " roles and " + std::to_string(m.servers().size()) +
            " servers: at most " + std::to_string(D::max_roles) + ", one server per role";
      return false;
    }
    if (m.settings().size() > D::max_settings) {
      why = std::to_string(m.settings().size()) + " settings, at most " + std::to_string(D::max_settings);
      return false;
    }
    d = D{};
    if (!fits(d.kind, m.kind(), "kind", why) || !fits(d.variant, m.variant(), "variant", why)) return false;
    for (std::size_t i = 0; i < m.roles().size(); ++i)
      if (!fits(d.roles[i], m.roles()[i], "role", why) || !fits(d.servers[i], m.servers()[i], "server", why))
        return false;
    for (const auto& s : m.settings()) {
      DeclaredSetting& out = d.settings[d.setting_count++];
      if (!fits(out.name, s.name(), "setting", why) || !fits(out.unit, s.unit(), "unit", why)) return false;
      if (std::isnan(s.min()) || std::isnan(s.max()) || !(s.min() <= s.max())) {
        why = "setting " + s.name() + "'s bounds are not numbers in order";
        return false;
      }
      out.min = s.min();
      out.max = s.max();
      out.count = s.count();
      out.command = s.command();
    }
    return true;
  }
  static std::string text(const D& d) {
    std::string s = std::string(D::get(d.kind)) + " " + std::string(D::get(d.variant));
    for (std::size_t i = 0; i < D::max_roles && !D::get(d.roles[i]).empty(); ++i)
      s += (i ? ", " : "; ") + std::string(D::get(d.roles[i])) + ": " + std::string(D::get(d.servers[i]));
    for (std::size_t i = 0; i < d.setting_count && i < D::max_settings; ++i)
      s += (i ? ", " : "; settings ") + std::string(D::get(d.settings[i].name));
    return s;
  }
  static bool parse(std::string_view, D&, std::string& why) {
    why = "a description is read, not sent";
    return false;
  }
};

}  // namespace saw::gateway::conversions
