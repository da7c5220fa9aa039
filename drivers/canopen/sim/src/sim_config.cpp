#include "saw/canopen/sim/sim_config.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "saw/deploy/params.hpp"

namespace saw::canopen::sim {

namespace {

using deploy::ConfigError;
using deploy::Params;

MotorParameters parse_motor(const Params& p) {
  MotorParameters m;
  m.motor_inertia = p.get_or<double>("motor_inertia", m.motor_inertia);
  m.load_inertia = p.get_or<double>("load_inertia", m.load_inertia);
  m.viscous_friction = p.get_or<double>("viscous_friction", m.viscous_friction);
  m.load_torque = p.get_or<double>("load_torque", m.load_torque);
  m.position_bandwidth_hz = p.get_or<double>("position_bandwidth_hz", m.position_bandwidth_hz);
  m.velocity_bandwidth_hz = p.get_or<double>("velocity_bandwidth_hz", m.velocity_bandwidth_hz);
  m.integration_step =
      p.get_or<std::chrono::nanoseconds>("integration_step", std::chrono::nanoseconds(m.integration_step))
          .count();
  try {
    m.check();
  } catch (const std::invalid_argument& e) {
    p.fail(e.what());
  }
  return m;
}

SimConfig parse_tree(const YAML::Node& root, const std::string& file) {
  const Params top(root, file, "");
  const std::filesystem::path directory = std::filesystem::path(file).parent_path();
  SimConfig c;
  c.bus = top.get_or<std::string>("bus", "");
  c.period = top.get_or<std::chrono::nanoseconds>("period", std::chrono::nanoseconds(c.period)).count();
  if (c.period < 50'000 || c.period > 100'000'000) top.fail_at("period", "must be 50us .. 100ms");

  top.mark_used("drives");
  const YAML::Node drives = root["drives"];
  if (!drives.IsDefined() || !drives.IsSequence() || drives.size() == 0)
    top.fail_at("drives", "expected a non-empty list of drives");
  std::set<int> nodes;
  for (std::size_t i = 0; i < drives.size(); ++i) {
    const Params d(drives[i], file, "drives[" + std::to_string(i) + "]");
    SimDriveConfig drive;
    const int node = static_cast<int>(d.get_in_range("node", 1, 127, 0));
    if (node == 0) d.fail_at("node", "required: a node-ID 1..127");
    if (std::abs(d.get<double>("node") - node) > 0) d.fail_at("node", "must be a whole number");
    if (!nodes.insert(node).second) d.fail_at("node", "node " + std::to_string(node) + " is simulated twice");
    drive.node = static_cast<std::uint8_t>(node);
    if (d.has("eds")) {
      std::filesystem::path eds = d.get<std::string>("eds");
      if (eds.is_relative() && !directory.empty()) eds = directory / eds;
      drive.eds = eds.string();
    }
    if (d.has("heartbeat_ms"))
      drive.heartbeat_ms = static_cast<std::uint16_t>(d.get_in_range("heartbeat_ms", 0, 65535, 0));
    drive.motor = parse_motor(d.child("motor"));
    d.check_all_used();
    c.drives.push_back(std::move(drive));
  }

  top.mark_used("faults");
  const YAML::Node faults = root["faults"];
  if (faults.IsDefined() && !faults.IsNull()) {
    if (!faults.IsSequence()) top.fail_at("faults", "expected a list such as [\"2:over-current:1.5\"]");
    for (std::size_t i = 0; i < faults.size(); ++i) {
      const auto [line, column] = deploy::location(faults[i]);
      const std::string key = "faults[" + std::to_string(i) + "]";
      if (!faults[i].IsScalar())
        throw ConfigError(file, line, column, key, "expected <node>:<kind>:<at seconds>");
      try {
        c.faults.push_back(parse_scheduled_fault(faults[i].Scalar()));
      } catch (const std::invalid_argument& e) {
        throw ConfigError(file, line, column, key, e.what());
      }
      if (!nodes.contains(c.faults.back().node))
        throw ConfigError(file, line, column, key,
                          "node " + std::to_string(c.faults.back().node) + " is not one of the drives");
    }
  }
  top.check_all_used();
  return c;
}

}  // namespace

SimConfig parse_sim_config(const std::string& yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file, e.mark.line + 1, e.mark.column + 1, "", "YAML syntax: " + e.msg);
  }
  try {
    return parse_tree(root, file);
  } catch (const YAML::Exception& e) {
    const bool placed = !e.mark.is_null();
    throw ConfigError(file, placed ? e.mark.line + 1 : 0, placed ? e.mark.column + 1 : 0, "",
                      "unexpected YAML shape: " + e.msg);
  }
}

SimConfig load_sim_config(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, 0, 0, "", "cannot read the file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_sim_config(ss.str(), path);
}

void check(const SimConfig& c) {
  if (c.drives.empty())
    throw std::invalid_argument("no drive to simulate (--node or a config file's drives:)");
  if (c.period < 50'000 || c.period > 100'000'000)
    throw std::invalid_argument("the period must be 50 us .. 100 ms");
  std::set<int> nodes;
  for (const auto& d : c.drives)
    if (!nodes.insert(d.node).second)
      throw std::invalid_argument("node " + std::to_string(d.node) + " is simulated twice");
  for (const auto& f : c.faults)
    if (!nodes.contains(f.node))
      throw std::invalid_argument("fault for node " + std::to_string(f.node) + ", which is not simulated");
}

}  // namespace saw::canopen::sim
