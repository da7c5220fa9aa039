// parse_deployment: a deployment file to a DeploymentSpec, every error with its file:line.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "saw/deploy/deployment_spec.hpp"
#include "saw/deploy/placement.hpp"

namespace saw::deploy {
namespace {

Location location_of(const YAML::Node& n, const std::string& file, const std::string& key) {
  const auto [line, column] = location(n);
  return {file, line, column, key};
}

// A deadline policy as written, before a task's period turns its window into periods: the
// deployment's default (`deployment: {deadline: ...}`), or the standard one.
struct DeadlineDefault {
  bool off = false;
  std::uint32_t in_a_row = DeadlinePolicy::standard().in_a_row;
  double share = DeadlinePolicy::standard().share;
  std::optional<std::chrono::nanoseconds> window;  // none: the standard number of periods
  std::optional<Params> at;                        // where it was written, for errors
};

// `deadline:` of `d` (a `task:` or the `deployment:` mapping): off, or {in_a_row, share, window},
// each key defaulting to `base`'s.
DeadlineDefault parse_deadline_keys(const Params& t, const DeadlineDefault& base) {
  if (!t.has("deadline")) {
    t.mark_used("deadline");
    return base;
  }
  DeadlineDefault r = base;
  if (!t.has_map("deadline")) {
    // `off`: lateness is counted and logged, never a fault.
    if (const auto v = t.get<std::string>("deadline"); v == "off" || v == "false") {
      r.off = true;
      return r;
    }
    t.fail_at("deadline", "expected off, or {in_a_row: N, share: S, window: T}");
  }
  const Params d = t.child("deadline");
  r.off = false;
  r.at = d;
  const double in_a_row = d.get_in_range("in_a_row", 0, 1e6, base.in_a_row);
  if (in_a_row != static_cast<double>(static_cast<std::uint32_t>(in_a_row)))
    d.fail_at("in_a_row", "expected a whole number of periods (0: not checked)");
  r.in_a_row = static_cast<std::uint32_t>(in_a_row);
  r.share = d.get_in_range("share", 0, 0.99, base.share);
  if (d.has("window")) r.window = d.get<std::chrono::nanoseconds>("window");
  return r;
}

// A task's policy: its `deadline:` over the deployment's default; the window in its periods.
DeadlinePolicy parse_deadline(const Params& t, std::chrono::nanoseconds period, const DeadlineDefault& base) {
  if (period.count() == 0) {
    if (t.has("deadline")) t.fail_at("deadline", "a continuous task (no period) has no deadline");
    t.mark_used("deadline");
    return {};
  }
  const DeadlineDefault d = parse_deadline_keys(t, base);
  if (d.off) return {};
  DeadlinePolicy policy{d.in_a_row, d.share, DeadlinePolicy::standard().window};
  if (d.window) {
    if (*d.window < 10 * period || *d.window > 3600 * std::chrono::seconds(1)) {
      const std::string why = "the share is judged over at least 10 periods and at most an hour";
      if (d.at) d.at->fail_at("window", why + " (a " + std::to_string(period.count()) + " ns period here)");
      t.fail_at("deadline", why);
    }
    policy.window = static_cast<std::uint32_t>(*d.window / period);
  }
  return policy;
}

std::optional<TaskConfig> parse_task(Params& p, const DeadlineDefault& deadline) {
  if (!p.has("task")) {
    (void)p.child("task");
    return std::nullopt;
  }
  Params t = p.child("task");
  TaskConfig c;
  c.period = t.get_or<std::chrono::nanoseconds>("period", std::chrono::nanoseconds(0));
  c.priority = static_cast<int>(t.get_in_range("priority", 0, 99, 0));
  c.cpu = static_cast<int>(t.get_in_range("cpu", -1, 1023, -1));
  if (c.period.count() != 0 && c.period < std::chrono::microseconds(10))
    t.fail_at("period", "a period under 10 us is not supported");
  c.offset = t.get_or<std::chrono::nanoseconds>("offset", std::chrono::nanoseconds(0));
  if (c.offset.count() < 0 || (c.offset.count() != 0 && c.offset >= c.period))
    t.fail_at("offset", "the phase must be at least 0 and less than the period");
  c.deadline = parse_deadline(t, c.period, deadline);
  c.history = t.get_or<std::chrono::nanoseconds>("history", std::chrono::nanoseconds(0));
  if (c.history.count() != 0 &&
      (c.period.count() == 0 || c.history > 60 * std::chrono::seconds(1) || c.history < c.period))
    t.fail_at("history", "a periodic task's history is at least a period and at most 60 s");
  return c;
}

// Plug-ins, relative to the file: loaded before any type is looked up.
void load_plugins(const YAML::Node& root, const Params& top, const std::string& directory,
                  ComponentRegistry& registry, DeploymentSpec& spec) {
  top.mark_used("plugins");
  const YAML::Node list = root["plugins"];
  if (!list.IsDefined() || list.IsNull()) return;
  if (!list.IsSequence()) top.fail_at("plugins", "expected a list of shared-library paths");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string key = "plugins[" + std::to_string(i) + "]";
    const Location at = location_of(list[i], spec.file, key);
    if (!list[i].IsScalar()) throw ConfigError(at, "expected a path to a shared library");
    std::filesystem::path path = list[i].as<std::string>();
    if (path.is_relative() && !directory.empty()) path = std::filesystem::path(directory) / path;
    try {
      registry.load_plugin(path.string());
    } catch (const std::exception& e) {
      throw ConfigError(at, std::string("plug-in not loaded: ") + e.what());
    }
    spec.plugins.push_back(path.string());
  }
}

// The `components:` list: each parsed by its type's parser; another host's only checked for
// its name and host.
void parse_components(const YAML::Node& root, const Params& top, const ComponentRegistry& registry,
                      Placement& place, const DeadlineDefault& deadline, DeploymentSpec& spec) {
  top.mark_used("components");
  const YAML::Node list = root["components"];
  if (!list.IsDefined() || !list.IsSequence() || list.size() == 0)
    top.fail_at("components", "expected a non-empty list of components");
  for (std::size_t i = 0; i < list.size(); ++i) {
    Params entry(list[i], spec.file, "components[" + std::to_string(i) + "]");
    const auto name = entry.get<std::string>("name");
    const auto type_name = entry.get<std::string>("type");
    const ComponentRegistry::Type* type = registry.find(type_name);
    if (type == nullptr)
      entry.fail_at("type",
                    "unknown component type '" + type_name + "' (known: " + registry.type_list() + ")");
    const bool seen =
        place.host_of.count(name) != 0 || std::any_of(spec.components.begin(), spec.components.end(),
                                                      [&](const ComponentSpec& c) { return c.name == name; });
    if (seen) entry.fail_at("name", "a component named '" + name + "' exists already");
    if (place.active) {
      const auto h = entry.get<std::string>("host");
      if (place.address.count(h) == 0)
        entry.fail_at("host", "no host '" + h + "' (hosts: " + place.names() + ")");
      place.host_of[name] = h;
      if (h != place.self) {  // another process's part of the file: checked there
        entry.mark_used("task");
        entry.mark_used("params");
        entry.check_all_used();
        continue;
      }
    } else if (entry.has("host")) {
      entry.fail_at("host", "placing a component needs a hosts: section");
    }
    ComponentContext ctx{name, parse_task(entry, deadline), spec.directory, &registry};
    Params params = entry.child("params");
    std::any config;
    try {
      config = type->parse(ctx, params);
    } catch (const ConfigError&) {
      throw;
    } catch (const std::exception& e) {
      entry.fail_at("params", e.what());
    }
    entry.check_all_used();
    spec.components.push_back(
        {name, type_name, std::move(config), location_of(list[i], spec.file, entry.path())});
  }
}

bool here_by_name(const DeploymentSpec& spec, const std::string& name) {
  return std::any_of(spec.components.begin(), spec.components.end(),
                     [&](const ComponentSpec& c) { return c.name == name; });
}

void parse_exports(const YAML::Node& root, const Params& top, DeploymentSpec& spec) {
  top.mark_used("exports");
  const YAML::Node exports = root["exports"];
  if (!exports.IsDefined() || exports.IsNull()) return;
  if (!exports.IsSequence()) top.fail_at("exports", "expected a list of {component, provided}");
  for (std::size_t i = 0; i < exports.size(); ++i) {
    Params e(exports[i], spec.file, "exports[" + std::to_string(i) + "]");
    const auto component = e.get<std::string>("component"), provided = e.get<std::string>("provided");
    e.check_all_used();
    if (!here_by_name(spec, component)) e.fail_at("component", "no component named '" + component + "'");
    spec.exports.push_back({component, provided, location_of(exports[i], spec.file, e.path())});
  }
}

// Placed on hosts: a server here with a client elsewhere is exported (and, for another machine,
// attached by this host's gateway); a server on another machine is mirrored here by the gateway.
void implied_by_placement(const YAML::Node& root, const Placement& place, DeploymentSpec& spec,
                          std::vector<std::string>& remote_attach, std::vector<std::string>& mirrors) {
  const auto add_unique = [](std::vector<std::string>& v, const std::string& x) {
    if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
  };
  const YAML::Node connections = root["connections"];
  // An absent key is an invalid node in yaml-cpp: asking its type throws, so ask whether it exists.
  if (!place.active || !connections.IsDefined() || !connections.IsSequence()) return;
  for (std::size_t i = 0; i < connections.size(); ++i) {
    const YAML::Node c = connections[i];
    const auto text = [&](const char* key) { return c[key] && c[key].IsScalar(); };
    if (!c.IsMap() || !text("client") || !text("server") || !text("provided")) continue;  // reported later
    const auto client = c["client"].as<std::string>(), server = c["server"].as<std::string>();
    const auto provided = c["provided"].as<std::string>();
    if (place.host_of.count(client) == 0 || place.host_of.count(server) == 0) continue;
    const auto& client_host = place.host_of.at(client);
    const auto& server_host = place.host_of.at(server);
    const std::string key = "connections[" + std::to_string(i) + "]";
    if (server_host == place.self && client_host != place.self) {
      const auto it = std::find_if(spec.exports.begin(), spec.exports.end(),
                                   [&](const ExportSpec& e) { return e.component == server; });
      if (it == spec.exports.end())
        spec.exports.push_back({server, provided, location_of(c, spec.file, key)});
      else if (it->provided != provided)
        throw ConfigError(location_of(c, spec.file, key),
                          "'" + server + "' is already exported with '" + it->provided +
                              "'; one interface per component crosses to other hosts");
      if (place.remote_machine(client_host)) add_unique(remote_attach, server);
    }
    if (client_host == place.self && server_host != place.self && place.remote_machine(server_host))
      add_unique(mirrors, server);
  }
}

// The packages' sections (a `gateway:`): each parsed by its owner, with what this host's placement
// implies (what crosses to other machines), even when the file does not write the section.
void parse_sections(const YAML::Node& root, const Params& top, const Placement& place,
                    const ComponentRegistry& registry, DeploymentSpec& spec) {
  std::vector<std::string> remote_clients, remote_servers;
  implied_by_placement(root, place, spec, remote_clients, remote_servers);
  for (const auto& [key, section] : registry.sections()) {
    SectionContext ctx;
    if (top.has(key)) {
      ctx.params = top.child(key);
      ctx.node = root[key];
      ctx.at = location_of(root[key], spec.file, key);
    } else {
      ctx.at = {spec.file, 0, 0, place.active ? "hosts" : key};
    }
    ctx.file = spec.file;
    ctx.directory = spec.directory;
    if (place.active) {
      ctx.host = place.self;
      ctx.address = place.address.at(place.self);
      ctx.host_entry.emplace(place.entry.at(place.self), spec.file, "hosts." + place.self);
    }
    for (const auto& e : spec.exports) ctx.exported.push_back(e.component);
    ctx.remote_clients = remote_clients;
    ctx.remote_servers = remote_servers;
    ctx.is_component = [&](const std::string& n) {
      return here_by_name(spec, n) || place.host_of.count(n) != 0;
    };
    std::optional<SectionValue> value;
    try {
      value = section.parse(ctx);
    } catch (const ConfigError&) {
      throw;
    } catch (const std::exception& e) {
      throw ConfigError(ctx.at, e.what());
    }
    if (ctx.params) ctx.params->check_all_used();
    if (value) spec.sections.push_back({key, std::move(*value), ctx.at});
  }
}

void parse_connections(const YAML::Node& root, const Params& top, const Placement& place,
                       DeploymentSpec& spec) {
  top.mark_used("connections");
  const YAML::Node connections = root["connections"];
  if (!connections.IsDefined() || connections.IsNull()) return;
  if (!connections.IsSequence()) top.fail_at("connections", "expected a list of connections");
  // Components a section presents here (arms a gateway imports) may be connected too.
  const auto imported = [&](const std::string& n) {
    return std::any_of(spec.sections.begin(), spec.sections.end(), [&](const SectionSpec& s) {
      return std::find(s.value.presents.begin(), s.value.presents.end(), n) != s.value.presents.end();
    });
  };
  for (std::size_t i = 0; i < connections.size(); ++i) {
    Params c(connections[i], spec.file, "connections[" + std::to_string(i) + "]");
    ConnectionSpec conn{c.get<std::string>("client"), c.get<std::string>("required"),
                        c.get<std::string>("server"), c.get<std::string>("provided"),
                        location_of(connections[i], spec.file, c.path())};
    c.check_all_used();
    if (place.active) {
      for (const auto& [key, who] : {std::pair{"client", conn.client}, std::pair{"server", conn.server}})
        if (place.host_of.count(who) == 0 && !imported(who))
          c.fail_at(key, "no component named '" + who + "'");
      if (!place.here(conn.client)) continue;  // made by the client's host
    }
    spec.connections.push_back(std::move(conn));
  }
}

void parse_record(const YAML::Node& root, const Params& top, const Placement& place, DeploymentSpec& spec) {
  if (!top.has("record")) return;
  Params r = top.child("record");
  RecordSpec rec;
  rec.at = location_of(root["record"], spec.file, "record");
  rec.file = r.get_or<std::string>("file", "");
  if (!rec.file.empty() && std::filesystem::path(rec.file).is_relative() && !spec.directory.empty())
    rec.file = (std::filesystem::path(spec.directory) / rec.file).string();
  rec.decimation = static_cast<int>(r.get_in_range("decimation", 1, 1e6, 1));
  const YAML::Node cols = root["record"]["columns"];
  r.mark_used("columns");
  if (!cols.IsDefined() || !cols.IsSequence() || cols.size() == 0)
    r.fail_at("columns", "expected a list of component.column");
  for (const auto& n : cols) {
    const Location at = location_of(n, spec.file, "record.columns");
    if (!n.IsScalar()) throw ConfigError(at, "expected component.column");
    const auto text = n.as<std::string>();
    const auto dot = text.find('.');
    if (dot == std::string::npos) throw ConfigError(at, "expected component.column, not '" + text + "'");
    // Placed on hosts: each host records its own components' columns.
    const auto component = text.substr(0, dot);
    if (place.active && place.host_of.count(component) != 0 && !place.here(component)) continue;
    rec.columns.push_back(text);
    rec.column_at.push_back(at);
  }
  spec.record = rec;
}

DeploymentSpec parse_tree(const YAML::Node& root, const std::string& file, ComponentRegistry& registry,
                          const std::string& host) {
  Params top(root, file, "");
  DeploymentSpec spec;
  spec.file = file;
  spec.directory = std::filesystem::path(file).parent_path().string();
  Params head = top.child("deployment");
  spec.name = head.get_or<std::string>("name", std::filesystem::path(file).stem().string());
  spec.clock =
      head.get_enum<Clock>("clock", {{"real", Clock::real}, {"stepped", Clock::stepped}}, Clock::real);
  load_plugins(root, top, spec.directory, registry, spec);
  std::vector<std::string> host_keys;
  for (const auto& [key, section] : registry.sections())
    host_keys.insert(host_keys.end(), section.host_keys.begin(), section.host_keys.end());
  Placement place = parse_placement(root, top, host, host_keys);
  // Every periodic task's deadline policy unless its `task:` says another (a qualified PC
  // tightens them all here).
  const DeadlineDefault deadline = parse_deadline_keys(head, DeadlineDefault{});
  parse_components(root, top, registry, place, deadline, spec);
  parse_exports(root, top, spec);
  parse_sections(root, top, place, registry, spec);
  parse_connections(root, top, place, spec);
  parse_record(root, top, place, spec);
  top.check_all_used();
  return spec;
}

}  // namespace

DeploymentSpec parse_deployment(const std::string& yaml_text, const std::string& file,
                                ComponentRegistry& registry, const std::string& host) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file, e.mark.line + 1, e.mark.column + 1, "", "YAML syntax: " + e.msg);
  }
  try {
    return parse_tree(root, file, registry, host);
  } catch (const YAML::Exception& e) {
    // A shape no check foresaw (each foreseen one is a ConfigError naming its key): still an
    // error that names the file and, where yaml-cpp knows it, the place.
    const bool placed = !e.mark.is_null();
    throw ConfigError(file, placed ? e.mark.line + 1 : 0, placed ? e.mark.column + 1 : 0, "",
                      "unexpected YAML shape: " + e.msg);
  }
}

DeploymentSpec load_deployment_spec(const std::string& path, ComponentRegistry& registry,
                                    const std::string& host) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, 0, 0, "", "cannot read the deployment file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_deployment(ss.str(), path, registry, host);
}

}  // namespace saw::deploy
