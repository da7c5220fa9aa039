#include "saw/deploy/deployment.hpp"

#include <algorithm>
#include <thread>

namespace saw::deploy {

Deployment::Deployment(DeploymentSpec spec) : spec_(std::move(spec)), manager_(std::make_unique<Manager>()) {}

Deployment::~Deployment() {
  if (manager_) stop();
}

void Deployment::make_components(const ComponentRegistry& registry) {
  for (const auto& c : spec_.components) {
    const auto* type = registry.find(c.type);
    if (type == nullptr) throw ConfigError(c.at, "unknown component type '" + c.type + "'");
    std::unique_ptr<Component> component;
    try {
      component = type->make(c.name, c.config);
    } catch (const std::exception& e) {
      throw ConfigError(c.at, "'" + c.name + "' (" + c.type + "): " + e.what());
    }
    if (component == nullptr || component->name() != c.name)
      throw ConfigError(c.at, "type '" + c.type + "' did not make a component named '" + c.name + "'");
    manager_->add(std::move(component));
  }
}

// What needs the built components: their interfaces and columns.
void Deployment::check_before_export(const ComponentRegistry& registry) const {
  for (const auto& e : spec_.exports) {
    const Component* c = manager_->find(e.component);
    if (c == nullptr) throw ConfigError(e.at, "no component named '" + e.component + "'");
    if (c->provided(e.provided) == nullptr)
      throw ConfigError(e.at, "'" + e.component + "' has no provided interface '" + e.provided + "'");
    if (!registry.exporter()) throw ConfigError(e.at, "this program cannot export interfaces");
  }
  if (!spec_.record) return;
  for (std::size_t i = 0; i < spec_.record->columns.size(); ++i) {
    const auto& text = spec_.record->columns[i];
    const auto dot = text.find('.');
    const Component* comp = manager_->find(text.substr(0, dot));
    const int index = comp == nullptr ? -1 : comp->state_table().find_column(text.substr(dot + 1));
    if (index < 0) throw ConfigError(spec_.record->column_at[i], "no state-table column '" + text + "'");
    const TypeInfo type = comp->state_table().column_type(static_cast<std::uint32_t>(index));
    if (format_for(type) == nullptr)
      throw ConfigError(spec_.record->column_at[i],
                        "'" + text + "' has a type the recorder cannot write: " + std::string(type.name));
  }
}

void Deployment::export_interfaces(const ComponentRegistry& registry) {
  for (const auto& e : spec_.exports) {
    try {
      exports_.push_back(registry.exporter()(*manager_->find(e.component), e.provided));
    } catch (const std::exception& ex) {
      throw ConfigError(e.at, ex.what());
    }
  }
}

// Checked by the manager (names and types); its message is kept whole.
void Deployment::connect_all() {
  for (const auto& c : spec_.connections) {
    try {
      manager_->connect(c.client, c.required, c.server, c.provided);
    } catch (const ConnectError& e) {
      throw ConfigError(c.at, e.what());
    }
  }
}

void Deployment::start_sections(bool before_connect) {
  for (const auto& s : spec_.sections) {
    if (s.value.before_connect != before_connect) continue;
    const Section* section = registry_->find_section(s.key);
    if (section == nullptr || !section->start) continue;
    try {
      sections_running_.push_back(section->start(s.value.value, *registry_));
    } catch (const std::exception& e) {
      throw ConfigError(s.at, e.what());
    }
  }
}

const SectionSpec* Deployment::section(const std::string& key) const noexcept {
  for (const auto& s : spec_.sections)
    if (s.key == key) return &s;
  return nullptr;
}

Deployment build_deployment(DeploymentSpec spec, const ComponentRegistry& registry) {
  Deployment d(std::move(spec));
  d.registry_ = &registry;
  d.make_components(registry);
  d.check_before_export(registry);
  d.export_interfaces(registry);
  for (const auto& make : registry.resolvers()) d.manager_->add_resolver(make());
  // What a section presents here (a gateway's mirrors and imports) must be in this host's bridge
  // before connect() looks for it; the handles stop it again if anything below fails.
  d.start_sections(true);
  d.connect_all();
  return d;
}

Deployment make_deployment(const std::string& yaml_text, const std::string& file, ComponentRegistry& registry,
                           const std::string& host) {
  return build_deployment(parse_deployment(yaml_text, file, registry, host), registry);
}

Deployment load_deployment(const std::string& path, ComponentRegistry& registry, const std::string& host) {
  return build_deployment(load_deployment_spec(path, registry, host), registry);
}

void Deployment::set_record_file(std::string path) {
  if (!spec_.record)
    throw ConfigError(spec_.file, 0, 0, "record", "--record needs a 'record:' section naming the columns");
  spec_.record->file = std::move(path);
}

void Deployment::start() {
  if (spec_.record && !spec_.record->file.empty() && !spec_.record->columns.empty()) {
    std::vector<Recorder::Column> columns;
    for (const auto& text : spec_.record->columns) {
      const auto dot = text.find('.');
      const Component* c = manager_->find(text.substr(0, dot));
      const auto index = static_cast<std::uint32_t>(c->state_table().find_column(text.substr(dot + 1)));
      columns.push_back({c, index, format_for(c->state_table().column_type(index)), text});
    }
    recorder_ = std::make_unique<Recorder>(spec_.record->file, std::move(columns), spec_.record->decimation);
  }
  if (spec_.clock == Clock::stepped) {
    manager_->start_stepped();
  } else {
    manager_->start();
    if (recorder_) recorder_->start_thread();
  }
  start_sections(false);
}

void Deployment::run_for(double seconds) {
  if (spec_.clock == Clock::stepped) {
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
  // Then the sections (the gateway): its mirrors served the tasks until they stopped, and its
  // attachments now publish FAULT for this host's components, as they would for a crash.
  while (!sections_running_.empty()) sections_running_.pop_back();
  if (recorder_) recorder_->stop();
}

}  // namespace saw::deploy
