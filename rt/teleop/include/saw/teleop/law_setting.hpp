// Setting: one declared setting of a control law, and how each kind of value is read and checked.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <string_view>

#include "saw/crtk.hpp"
#include "saw/deploy/params.hpp"

namespace saw::teleop {

inline constexpr double unbounded = std::numeric_limits<double>::infinity();

// Declared once, a setting becomes: the deployment parameter `name` (checked against the
// bounds, errors at file:line:key), the write command `set_<name>` when `command` (refused and
// counted outside the bounds, the bounds declared to the bridge and the gateway), a state column
// and read command `name` (the value in force), and a row of docs/teleop-laws.md.
// `min`/`max` bound every number of the value (±unbounded: any finite number).
template <class Settings, class T>
struct Setting {
  using Value = T;
  std::string_view name;
  std::string_view unit;
  double min = -unbounded, max = unbounded;
  T Settings::*member = nullptr;
  std::string_view help;
  bool command = true;  // false: fixed by the deployment, read back only
  // An invariant beyond the bounds (nullptr: none), and what to say when it fails.
  bool (*valid)(const T&) noexcept = nullptr;
  std::string_view invalid_why = {};
};

// A value a law computes and shows (a bilateral law's energy per port, a passivity controller's
// damping): a state column and read command `name` of the task, recorded and exported like its
// own. Declared in `declared_readouts`, after the member it reads.
template <class L, class T>
struct Readout {
  std::string_view name;
  std::string_view unit;
  T L::*member = nullptr;
  std::string_view help;
};

inline std::string setting_number(double v) {
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// How a value type is read from a deployment, checked and shown. Specialise it for a setting
// of another type (the collaborative law's Prediction and OffsetLimits are examples); `count`,
// the numbers in a value, is what the component's description says of it (0 when absent).
template <class T>
struct SettingCodec;

template <>
struct SettingCodec<double> {
  static constexpr std::string_view shape = "number";
  static constexpr std::uint32_t count = 1;
  static constexpr bool declares_limits = true;
  static bool within(const double& v, double lo, double hi) noexcept {
    return std::isfinite(v) && v >= lo && v <= hi;
  }
  static double parse(const deploy::Params& p, const std::string& key, double lo, double hi,
                      double fallback) {
    if (std::isinf(lo) && std::isinf(hi)) {
      const double v = p.get_or<double>(key, fallback);
      if (!std::isfinite(v)) p.fail_at(key, "must be finite");
      return v;
    }
    return p.get_in_range(key, lo, hi, fallback);
  }
  static std::string text(const double& v) { return setting_number(v); }
};

template <>
struct SettingCodec<bool> {
  static constexpr std::string_view shape = "true/false";
  static constexpr std::uint32_t count = 1;
  static constexpr bool declares_limits = false;
  static bool within(const bool&, double, double) noexcept { return true; }
  static bool parse(const deploy::Params& p, const std::string& key, double, double, bool fallback) {
    return p.get_or<bool>(key, fallback);
  }
  static std::string text(const bool& v) { return v ? "true" : "false"; }
};

template <>
struct SettingCodec<Vec3> {
  static constexpr std::string_view shape = "[x, y, z]";
  static constexpr std::uint32_t count = 3;
  static constexpr bool declares_limits = true;
  static bool within(const Vec3& v, double lo, double hi) noexcept {
    for (double x : v)
      if (!SettingCodec<double>::within(x, lo, hi)) return false;
    return true;
  }
  static Vec3 parse(const deploy::Params& p, const std::string& key, double lo, double hi,
                    const Vec3& fallback) {
    const Vec3 v = p.get_or<Vec3>(key, fallback);
    if (!within(v, lo, hi))
      p.fail_at(key, "each entry must be finite" +
                         (std::isinf(lo) && std::isinf(hi)
                              ? std::string()
                              : ", within [" + setting_number(lo) + ", " + setting_number(hi) + "]"));
    return v;
  }
  static std::string text(const Vec3& v) {
    return "[" + setting_number(v[0]) + ", " + setting_number(v[1]) + ", " + setting_number(v[2]) + "]";
  }
};

// A value with one number per device: {master: …, slave: …} (teleop::Gains, ForceLimits).
template <class T>
requires requires(T t) {
  { t.master } -> std::same_as<double&>;
  { t.slave } -> std::same_as<double&>;
}
struct SettingCodec<T> {
  static constexpr std::string_view shape = "{master, slave}";
  static constexpr std::uint32_t count = 2;
  static constexpr bool declares_limits = true;
  static bool within(const T& v, double lo, double hi) noexcept {
    return SettingCodec<double>::within(v.master, lo, hi) && SettingCodec<double>::within(v.slave, lo, hi);
  }
  static T parse(const deploy::Params& p, const std::string& key, double lo, double hi, const T& fallback) {
    const deploy::Params c = p.child(key);
    T v = fallback;
    v.master = SettingCodec<double>::parse(c, "master", lo, hi, fallback.master);
    v.slave = SettingCodec<double>::parse(c, "slave", lo, hi, fallback.slave);
    return v;
  }
  static std::string text(const T& v) {
    return "{master: " + setting_number(v.master) + ", slave: " + setting_number(v.slave) + "}";
  }
};

}  // namespace saw::teleop
