#include "saw/deploy/params.hpp"

#include <cmath>
#include <cstdio>

namespace saw::deploy {

std::pair<int, int> location(const YAML::Node& n) {
  if (!n.IsDefined()) return {0, 0};
  const auto m = n.Mark();
  return {m.line + 1, m.column + 1};
}

Params::Params(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)),
      file_(std::move(file)),
      path_(std::move(path)),
      used_(std::make_shared<std::set<std::string>>()),
      children_(std::make_shared<std::vector<Params>>()) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) fail("expected a mapping of parameters");
}

bool Params::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

bool Params::has_map(const std::string& key) const { return has(key) && node_[key].IsMap(); }

void Params::fail(const std::string& what) const {
  const auto [line, column] = location(node_);
  throw ConfigError(file_, line, column, path_, what);
}

void Params::fail_at(const std::string& key, const std::string& what) const {
  const YAML::Node v = node_.IsMap() ? node_[key] : YAML::Node();
  auto [line, column] = location(v);
  if (line == 0) std::tie(line, column) = location(node_);  // a missing key: point at its mapping
  throw ConfigError(file_, line, column, key_path(key), what);
}

YAML::Node Params::value(const std::string& key) const {
  used_->insert(key);
  if (!has(key)) fail_at(key, "required parameter is missing");
  return node_[key];
}

namespace {
template <class T>
T scalar(const Params& p, const YAML::Node& v, const std::string& key, const char* type) {
  if (!v.IsScalar()) p.fail_at(key, std::string("expected ") + type);
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    p.fail_at(key, std::string("expected ") + type + ", got '" + v.Scalar() + "'");
  }
}
}  // namespace

template <>
double Params::get<double>(const std::string& key) const {
  const double d = scalar<double>(*this, value(key), key, "a number");
  if (!std::isfinite(d)) fail_at(key, "expected a finite number");
  return d;
}
template <>
int Params::get<int>(const std::string& key) const {
  return scalar<int>(*this, value(key), key, "an integer");
}
template <>
std::int64_t Params::get<std::int64_t>(const std::string& key) const {
  return scalar<std::int64_t>(*this, value(key), key, "an integer");
}
template <>
bool Params::get<bool>(const std::string& key) const {
  return scalar<bool>(*this, value(key), key, "true or false");
}
template <>
std::string Params::get<std::string>(const std::string& key) const {
  return scalar<std::string>(*this, value(key), key, "a string");
}
template <>
std::vector<double> Params::get<std::vector<double>>(const std::string& key) const {
  const YAML::Node v = value(key);
  if (!v.IsSequence()) fail_at(key, "expected a list of numbers");
  std::vector<double> out;
  for (const auto& e : v) {
    try {
      out.push_back(e.as<double>());
    } catch (const YAML::Exception&) {
      const auto [line, column] = location(e);
      throw ConfigError(file_, line, column, key_path(key), "expected a number, got '" + e.Scalar() + "'");
    }
  }
  return out;
}
template <>
std::vector<std::string> Params::get<std::vector<std::string>>(const std::string& key) const {
  const YAML::Node v = value(key);
  if (!v.IsSequence()) fail_at(key, "expected a list of names");
  std::vector<std::string> out;
  for (const auto& e : v) {
    if (!e.IsScalar()) {
      const auto [line, column] = location(e);
      throw ConfigError(file_, line, column, key_path(key), "expected a name");
    }
    out.push_back(e.Scalar());
  }
  return out;
}
template <>
Vec3 Params::get<Vec3>(const std::string& key) const {
  const auto v = get<std::vector<double>>(key);
  if (v.size() != 3) fail_at(key, "expected a list of exactly 3 numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}
template <>
std::vector<Vec3> Params::get<std::vector<Vec3>>(const std::string& key) const {
  const YAML::Node v = value(key);
  if (!v.IsSequence()) fail_at(key, "expected a list of [x, y, z] points");
  std::vector<Vec3> out;
  for (const auto& e : v) {
    const auto [line, column] = location(e);
    if (!e.IsSequence() || e.size() != 3)
      throw ConfigError(file_, line, column, key_path(key), "expected a point [x, y, z]");
    Vec3 p{};
    for (std::size_t i = 0; i < 3; ++i) {
      try {
        p[i] = e[i].as<double>();
      } catch (const YAML::Exception&) {
        throw ConfigError(file_, line, column, key_path(key),
                          "expected a number, got '" + e[i].Scalar() + "'");
      }
      if (!std::isfinite(p[i])) throw ConfigError(file_, line, column, key_path(key), "not a finite number");
    }
    out.push_back(p);
  }
  return out;
}
template <>
std::chrono::nanoseconds Params::get<std::chrono::nanoseconds>(const std::string& key) const {
  const YAML::Node v = value(key);
  if (!v.IsScalar()) fail_at(key, "expected a duration such as 1ms, 500us, 2s or a number of seconds");
  const std::string text = v.Scalar();
  static const std::vector<std::pair<std::string, double>> units = {
      {"ns", 1e-9}, {"us", 1e-6}, {"ms", 1e-3}, {"s", 1}};
  double scale = 1, number = 0;
  std::string digits = text;
  for (const auto& [suffix, factor] : units)
    if (text.size() > suffix.size() &&
        text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0) {
      digits = text.substr(0, text.size() - suffix.size());
      scale = factor;
      break;
    }
  try {
    std::size_t used = 0;
    number = std::stod(digits, &used);
    if (used != digits.size()) throw std::invalid_argument(text);
  } catch (const std::exception&) {
    fail_at(key, "'" + text + "' is not a duration (examples: 1ms, 500us, 2s, 0.001)");
  }
  if (!(number >= 0) || !std::isfinite(number))
    fail_at(key, "'" + text + "' must be a non-negative duration");
  return std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(number * scale * 1e9)));
}

double Params::get_in_range(const std::string& key, double lo, double hi, double fallback) const {
  if (!has(key)) {
    used_->insert(key);
    return fallback;
  }
  const double d = get<double>(key);
  if (d < lo || d > hi)
    fail_at(key,
            std::to_string(d) + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return d;
}

Params Params::child(const std::string& key) const {
  used_->insert(key);
  YAML::Node n = has(key) ? node_[key] : YAML::Node(YAML::NodeType::Null);
  Params c(n, file_, key_path(key));
  children_->push_back(c);
  return c;
}

void Params::check_all_used() const {
  if (node_.IsMap())
    for (const auto& kv : node_) {
      if (!kv.first.IsScalar()) {
        const auto [line, column] = location(kv.first);
        throw ConfigError(file_, line, column, path_, "a key must be a name, not a list or mapping");
      }
      const auto key = kv.first.as<std::string>();
      if (!used_->count(key)) {
        const auto [line, column] = location(kv.first);
        throw ConfigError(file_, line, column, key_path(key), "unknown parameter (misspelt?)");
      }
    }
  for (const auto& c : *children_) c.check_all_used();
}

std::int64_t Params::get_duration_in(const std::string& key, std::chrono::nanoseconds fallback,
                                     std::chrono::nanoseconds lo, std::chrono::nanoseconds hi,
                                     const char* what) const {
  const auto d = get_or<std::chrono::nanoseconds>(key, fallback);
  if (d >= lo && d <= hi) return d.count();
  if (what != nullptr) fail_at(key, what);
  char b[128];
  std::snprintf(b, sizeof b, "must be from %g to %g s", static_cast<double>(lo.count()) * 1e-9,
                static_cast<double>(hi.count()) * 1e-9);
  fail_at(key, b);
}

double seconds_in_range(const Params& p, const std::string& key, std::chrono::nanoseconds fallback, double lo,
                        double hi) {
  const double s = static_cast<double>(p.get_or<std::chrono::nanoseconds>(key, fallback).count()) * 1e-9;
  if (!(s >= lo && s <= hi)) {
    char b[96];
    std::snprintf(b, sizeof b, "%g s is out of range [%g, %g] s", s, lo, hi);
    p.fail_at(key, b);
  }
  return s;
}

}  // namespace saw::deploy
