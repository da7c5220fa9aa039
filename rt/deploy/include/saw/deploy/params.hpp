// Params: a typed, located view of one YAML mapping of a deployment file.
#pragma once

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "saw/crtk.hpp"
#include "saw/deploy/config_error.hpp"

namespace saw::deploy {

// Every error names the file, the line and column of the offending node, and the dotted key.
// Keys that are never asked for are reported by check_all_used(): typos do not pass silently.
class Params {
 public:
  Params(YAML::Node node, std::string file, std::string path);

  const std::string& file() const noexcept { return file_; }
  const std::string& path() const noexcept { return path_; }
  bool has(const std::string& key) const;
  // The key is there and holds a mapping (a key that takes a scalar or a mapping tells them apart).
  bool has_map(const std::string& key) const;

  // Supported T: double, int, std::int64_t, bool, std::string, saw::Vec3, std::vector<double>,
  // std::vector<std::string>, std::vector<saw::Vec3> (a list of [x, y, z]),
  // std::chrono::nanoseconds (seconds as a number, or "10ms", "500us", "2s", "100ns").
  template <class T>
  T get(const std::string& key) const;
  template <class T>
  T get_or(const std::string& key, T fallback) const {
    return has(key) ? get<T>(key) : fallback;
  }
  double get_in_range(const std::string& key, double lo, double hi, double fallback) const;
  // A duration within [lo, hi] (fallback when absent), in ns; outside it, an error naming the
  // range in seconds, or `what` when given (\"at least three periods\").
  std::int64_t get_duration_in(const std::string& key, std::chrono::nanoseconds fallback,
                               std::chrono::nanoseconds lo, std::chrono::nanoseconds hi,
                               const char* what = nullptr) const;
  template <class E>
  E get_enum(const std::string& key, const std::vector<std::pair<std::string, E>>& values, E fallback) const {
    if (!has(key)) return fallback;
    const auto text = get<std::string>(key);
    std::string accepted;
    for (const auto& [name, value] : values) {
      if (name == text) return value;
      accepted += (accepted.empty() ? "" : ", ") + name;
    }
    fail_at(key, "'" + text + "' is not one of: " + accepted);
  }
  // For keys read directly from the YAML (lists): they count as used.
  void mark_used(const std::string& key) const { used_->insert(key); }
  // A nested mapping (an empty one if absent).
  Params child(const std::string& key) const;

  // Throws for the first key of this mapping (and of children handed out) never read.
  void check_all_used() const;
  [[noreturn]] void fail_at(const std::string& key, const std::string& what) const;
  [[noreturn]] void fail(const std::string& what) const;

 private:
  YAML::Node value(const std::string& key) const;
  std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  YAML::Node node_;
  std::string file_, path_;
  std::shared_ptr<std::set<std::string>> used_;
  std::shared_ptr<std::vector<Params>> children_;
};

// A duration parameter in seconds within [lo, hi] s (fallback when absent).
double seconds_in_range(const Params& p, const std::string& key, std::chrono::nanoseconds fallback, double lo,
                        double hi);

// 1-based line and column of a node (0 if it has no mark).
std::pair<int, int> location(const YAML::Node& n);

}  // namespace saw::deploy
