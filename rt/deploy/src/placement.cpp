#include "saw/deploy/placement.hpp"

namespace saw::deploy {

std::string Placement::names() const {
  std::string s;
  for (const auto& a : address) s += (s.empty() ? "" : ", ") + a.first;
  return s;
}

Placement parse_placement(const YAML::Node& root, const Params& top, const std::string& host,
                          const std::vector<std::string>& section_keys) {
  Placement p;
  if (!top.has("hosts")) {
    if (!host.empty())
      throw ConfigError(top.file(), 0, 0, "hosts",
                        "--host " + host + " given, but the file places nothing on hosts");
    return p;
  }
  top.mark_used("hosts");
  const YAML::Node hosts = root["hosts"];
  if (!hosts.IsMap() || hosts.size() == 0) top.fail_at("hosts", "expected a mapping of host names");
  for (const auto& h : hosts) {
    if (!h.first.IsScalar()) top.fail_at("hosts", "a host's name must be a name, not a list or mapping");
    const auto name = h.first.as<std::string>();
    Params entry(h.second.IsNull() ? YAML::Node(YAML::NodeType::Map) : h.second, top.file(), "hosts." + name);
    p.address[name] = entry.get_or<std::string>("address", "");
    // Keys a package's section owns (the gateway's, for this host): read by that section.
    for (const auto& k : section_keys) entry.mark_used(k);
    p.entry.emplace(name, h.second.IsNull() ? YAML::Node(YAML::NodeType::Map) : h.second);
    entry.check_all_used();
  }
  p.active = true;
  if (host.empty())
    top.fail_at("hosts", "this deployment places components on hosts " + p.names() +
                             ": run saw-rt with --host NAME to run one of them");
  if (p.address.count(host) == 0) top.fail_at("hosts", "no host '" + host + "' (hosts: " + p.names() + ")");
  p.self = host;
  return p;
}

}  // namespace saw::deploy
