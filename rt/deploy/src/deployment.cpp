#include "saw/deploy/deployment.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace saw::deploy {
namespace {

std::optional<TaskConfig> parse_task(Params& p) {
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
  return c;
}

}  // namespace

Deployment parse_deployment(const std::string& yaml_text, const std::string& file,
                            const ComponentRegistry& registry, const std::string& host) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file, e.mark.line + 1, e.mark.column + 1, "", "YAML syntax: " + e.msg);
  }
  Params top(root, file, "");
  Deployment d;
  d.file_ = file;
  const std::string directory = std::filesystem::path(file).parent_path().string();
  Params head = top.child("deployment");
  d.name_ = head.get_or<std::string>("name", std::filesystem::path(file).stem().string());
  d.clock_ = head.get_enum<Clock>("clock", {{"real", Clock::real}, {"stepped", Clock::stepped}}, Clock::real);
  Placement place = parse_placement(root, top, host);

  // Components: each built by its registered factory from its own parameters.
  top.mark_used("components");  // a list: walked below
  const YAML::Node list = root["components"];
  if (!list.IsDefined() || !list.IsSequence() || list.size() == 0)
    top.fail_at("components", "expected a non-empty list of components");
  std::vector<Params> all_params;
  for (std::size_t i = 0; i < list.size(); ++i) {
    Params entry(list[i], file, "components[" + std::to_string(i) + "]");
    const auto name = entry.get<std::string>("name");
    const auto type = entry.get<std::string>("type");
    const Factory* factory = registry.find(type);
    if (factory == nullptr)
      entry.fail_at("type", "unknown component type '" + type + "' (known: " + registry.type_list() + ")");
    if (d.manager_->find(name) != nullptr || place.host_of.count(name) != 0)
      entry.fail_at("name", "a component named '" + name + "' exists already");
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
    auto task = parse_task(entry);
    Params params = entry.child("params");
    FactoryContext ctx{name, task, params, directory};
    std::unique_ptr<Component> component;
    try {
      component = (*factory)(ctx);
    } catch (const ConfigError&) {
      throw;
    } catch (const std::exception& e) {
      entry.fail_at("params", e.what());
    }
    entry.check_all_used();
    d.manager_->add(std::move(component));
  }

  // Exports: interfaces other processes may connect to (before any connection is made).
  top.mark_used("exports");
  const YAML::Node exports = root["exports"];
  if (exports.IsDefined() && !exports.IsNull()) {
    if (!exports.IsSequence()) top.fail_at("exports", "expected a list of {component, provided}");
    for (std::size_t i = 0; i < exports.size(); ++i) {
      Params e(exports[i], file, "exports[" + std::to_string(i) + "]");
      const auto component = e.get<std::string>("component"), provided = e.get<std::string>("provided");
      e.check_all_used();
      Component* c = d.manager_->find(component);
      if (c == nullptr) e.fail_at("component", "no component named '" + component + "'");
      if (c->provided(provided) == nullptr)
        e.fail_at("provided", "'" + component + "' has no provided interface '" + provided + "'");
      if (!registry.exporter()) e.fail("this program cannot export interfaces");
      try {
        d.exports_.push_back(registry.exporter()(*c, provided));
        d.exported_names_.push_back(component);
        d.exported_interface_[component] = provided;
      } catch (const std::exception& ex) {
        e.fail(ex.what());
      }
    }
  }
  for (const auto& make : registry.resolvers()) d.manager_->add_resolver(make());

  // Placed on hosts: a server here with a client elsewhere is exported (and, for another
  // machine, attached by this host's gateway); a server on another machine is mirrored here by
  // the gateway, so that connect() finds it in this host's bridge.
  std::vector<std::string> remote_attach, mirrors;
  const auto add_unique = [](std::vector<std::string>& v, const std::string& x) {
    if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
  };
  if (place.active && root["connections"].IsSequence()) {
    const YAML::Node connections = root["connections"];
    for (std::size_t i = 0; i < connections.size(); ++i) {
      const YAML::Node c = connections[i];
      if (!c.IsMap() || !c["client"] || !c["server"] || !c["provided"]) continue;  // reported below
      const auto client = c["client"].as<std::string>(), server = c["server"].as<std::string>();
      const auto provided = c["provided"].as<std::string>();
      if (place.host_of.count(client) == 0 || place.host_of.count(server) == 0) continue;
      const auto& client_host = place.host_of[client];
      const auto& server_host = place.host_of[server];
      if (server_host == place.self && client_host != place.self) {
        if (auto it = d.exported_interface_.find(server); it == d.exported_interface_.end()) {
          Component* comp = d.manager_->find(server);
          if (comp == nullptr || comp->provided(provided) == nullptr) continue;  // reported below
          if (!registry.exporter())
            throw ConfigError(file, 0, 0, "hosts", "this program cannot export interfaces");
          d.exports_.push_back(registry.exporter()(*comp, provided));
          d.exported_names_.push_back(server);
          d.exported_interface_[server] = provided;
        } else if (it->second != provided) {
          Params(c, file, "connections[" + std::to_string(i) + "]")
              .fail("'" + server + "' is already exported with '" + it->second +
                    "'; one interface per component crosses to other hosts");
        }
        if (place.remote_machine(client_host)) add_unique(remote_attach, server);
      }
      if (client_host == place.self && server_host != place.self && place.remote_machine(server_host))
        add_unique(mirrors, server);
    }
  }
  // The DDS gateway, started with the deployment: maps the exported interfaces to DDS.
  bool interfaces_named = false;
  if (top.has("gateway")) {
    Params g = top.child("gateway");
    GatewaySpec spec;
    for (const auto& e : d.exported_names_) spec.attach.push_back(e);
    spec.attach = g.get_or<std::vector<std::string>>("attach", spec.attach);
    // The da Vinci stream: foreign CRTK arms presented here (rt/[namespace/]<arm>/measured_cp, ...).
    if (g.has("import")) {
      g.mark_used("import");
      const YAML::Node import_list = root["gateway"]["import"];
      if (!import_list.IsSequence()) g.fail_at("import", "expected a list of {component, arm}");
      for (std::size_t i = 0; i < import_list.size(); ++i) {
        Params im(import_list[i], file, "gateway.import[" + std::to_string(i) + "]");
        const auto component = im.get<std::string>("component");
        const auto arm = im.get_or<std::string>("arm", component);
        im.check_all_used();
        if (d.manager_->find(component) != nullptr || place.host_of.count(component) != 0)
          im.fail_at("component", "a component named '" + component + "' exists already");
        spec.imports.emplace_back(component, arm);
      }
    }
    spec.ros_namespace = g.get_or<std::string>("namespace", "");
    for (const auto& a : spec.attach)
      if (std::find(d.exported_names_.begin(), d.exported_names_.end(), a) == d.exported_names_.end())
        g.fail_at("attach", "'" + a + "' is not exported by this deployment (see exports:)");
    if (spec.attach.empty() && spec.imports.empty() && remote_attach.empty() && mirrors.empty())
      g.fail("nothing to map: this deployment exports no interface (see exports:)");
    spec.domain = static_cast<int>(g.get_in_range("domain", 0, 232, 0));
    if (g.has("domain") && g.get<double>("domain") != spec.domain) g.fail_at("domain", "expected an integer");
    interfaces_named = g.has("interfaces");
    spec.interfaces = g.get_or<std::vector<std::string>>("interfaces", spec.interfaces);
    if (spec.interfaces.empty()) g.fail_at("interfaces", "at least one interface address");
    spec.decimation = static_cast<int>(g.get_in_range("decimation", 1, 1000, 1));
    g.check_all_used();
    if (!registry.gateway_launcher()) g.fail("this program cannot start a gateway");
    d.gateway_ = spec;
    d.launch_gateway_ = registry.gateway_launcher();
  }
  const bool imports = d.gateway_ && !d.gateway_->imports.empty();
  if (!remote_attach.empty() || !mirrors.empty() || imports) {
    if (!registry.gateway_launcher())
      throw ConfigError(file, 0, 0, "hosts", "this program cannot start a gateway to reach other hosts");
    if (!d.gateway_) {
      d.gateway_ = GatewaySpec{};
      d.gateway_->attach.clear();
    }
    for (const auto& a : remote_attach) add_unique(d.gateway_->attach, a);
    if (!interfaces_named && place.active && !place.address[place.self].empty())
      d.gateway_->interfaces = {place.address[place.self]};
    d.gateway_->mirrors = mirrors;
    d.launch_gateway_ = registry.gateway_launcher();
    // Mirrors and imports must be in this host's bridge before connect() looks for them.
    if (!mirrors.empty() || imports) {
      try {
        d.gateway_process_ = d.launch_gateway_(*d.gateway_);
      } catch (const std::exception& e) {
        throw ConfigError(file, 0, 0, "hosts", e.what());
      }
    }
  }

  // Connections, checked by the manager (names and types); its message is kept whole.
  top.mark_used("connections");
  const YAML::Node connections = root["connections"];
  if (connections.IsDefined() && !connections.IsNull()) {
    if (!connections.IsSequence()) top.fail_at("connections", "expected a list of connections");
    for (std::size_t i = 0; i < connections.size(); ++i) {
      Params c(connections[i], file, "connections[" + std::to_string(i) + "]");
      const auto client = c.get<std::string>("client"), required = c.get<std::string>("required");
      const auto server = c.get<std::string>("server"), provided = c.get<std::string>("provided");
      c.check_all_used();
      if (place.active) {
        const auto imported = [&](const std::string& n) {
          return d.gateway_ && std::any_of(d.gateway_->imports.begin(), d.gateway_->imports.end(),
                                           [&](const auto& im) { return im.first == n; });
        };
        for (const auto& [key, who] : {std::pair{"client", client}, std::pair{"server", server}})
          if (place.host_of.count(who) == 0 && !imported(who))
            c.fail_at(key, "no component named '" + who + "'");
        if (!place.here(client)) continue;  // made by the client's host
      }
      try {
        d.manager_->connect(client, required, server, provided);
      } catch (const ConnectError& e) {
        c.fail(e.what());
      }
    }
  }

  // Recording: the columns must exist and be of a type the recorder can write.
  if (top.has("record")) {
    Params r = top.child("record");
    RecordSpec spec;
    spec.file = r.get_or<std::string>("file", "");
    if (!spec.file.empty() && std::filesystem::path(spec.file).is_relative() && !directory.empty())
      spec.file = (std::filesystem::path(directory) / spec.file).string();
    spec.decimation = static_cast<int>(r.get_in_range("decimation", 1, 1e6, 1));
    const YAML::Node cols = root["record"]["columns"];
    r.mark_used("columns");
    if (!cols.IsDefined() || !cols.IsSequence() || cols.size() == 0)
      r.fail_at("columns", "expected a list of component.column");
    for (const auto& n : cols) {
      const auto text = n.as<std::string>();
      const auto dot = text.find('.');
      const auto [line, column] = location(n);
      // Placed on hosts: each host records its own components' columns.
      if (dot != std::string::npos && place.active && place.host_of.count(text.substr(0, dot)) != 0 &&
          !place.here(text.substr(0, dot)))
        continue;
      const Component* comp = dot == std::string::npos ? nullptr : d.manager_->find(text.substr(0, dot));
      const int index = comp == nullptr ? -1 : comp->state_table().find_column(text.substr(dot + 1));
      if (index < 0)
        throw ConfigError(file, line, column, "record.columns", "no state-table column '" + text + "'");
      if (format_for(comp->state_table().column_type(static_cast<std::uint32_t>(index))) == nullptr)
        throw ConfigError(
            file, line, column, "record.columns",
            "'" + text + "' has a type the recorder cannot write: " +
                std::string(comp->state_table().column_type(static_cast<std::uint32_t>(index)).name));
      spec.columns.push_back(text);
    }
    const auto [line, column] = location(root["record"]);
    d.record_line_ = line;
    d.record_column_ = column;
    d.record_ = spec;
  }
  top.check_all_used();
  return d;
}

Deployment load_deployment(const std::string& path, const ComponentRegistry& registry,
                           const std::string& host) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, 0, 0, "", "cannot read the deployment file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_deployment(ss.str(), path, registry, host);
}

void Deployment::set_record_file(std::string path) {
  if (!record_)
    throw ConfigError(file_, 0, 0, "record", "--record needs a 'record:' section naming the columns");
  record_->file = std::move(path);
}

void Deployment::start() {
  if (record_ && !record_->file.empty() && !record_->columns.empty()) {
    std::vector<Recorder::Column> columns;
    for (const auto& text : record_->columns) {
      const auto dot = text.find('.');
      const Component* c = manager_->find(text.substr(0, dot));
      const auto index = static_cast<std::uint32_t>(c->state_table().find_column(text.substr(dot + 1)));
      columns.push_back({c, index, format_for(c->state_table().column_type(index)), text});
    }
    recorder_ = std::make_unique<Recorder>(record_->file, std::move(columns), record_->decimation);
  }
  if (clock_ == Clock::stepped) {
    manager_->start_stepped();
  } else {
    manager_->start();
    if (recorder_) recorder_->start_thread();
  }
  if (gateway_ && !gateway_process_) gateway_process_ = launch_gateway_(*gateway_);
}

void Deployment::run_for(double seconds) {
  if (clock_ == Clock::stepped) {
    const TimeNs end = manager_->simulated_time() + static_cast<TimeNs>(seconds * 1e9);
    // Poll the recorder often enough that the ring (default 256 rows) never laps it.
    while (manager_->simulated_time() < end) {
      manager_->step_until(std::min(end, manager_->simulated_time() + 50'000'000));
      if (recorder_) recorder_->poll();
    }
  } else {
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  }
}

void Deployment::stop() {
  manager_->stop();
  // Then the gateway: its mirrors served the tasks until they stopped, and its attachments now
  // publish FAULT for this host's components, as they would for a crash.
  gateway_process_.reset();
  if (recorder_) recorder_->stop();
}

}  // namespace saw::deploy
