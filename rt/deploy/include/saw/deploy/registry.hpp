// ComponentRegistry: the component types a deployment file may name, and how to build each.
#pragma once

#include <any>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <typeindex>
#include <typeinfo>
#include <vector>

#include "saw/component.hpp"
#include "saw/deploy/params.hpp"
#include "saw/deploy/section.hpp"
#include "saw/manager.hpp"
#include "saw/task.hpp"

namespace saw::deploy {

// What a type's parser gets besides its `params:`: the component's name, its `task:` block
// (absent → the type's default) and the deployment file's directory (for relative paths).
class ComponentRegistry;

struct ComponentContext {
  std::string name;
  std::optional<TaskConfig> task;
  std::string directory;
  // The registry the deployment is parsed with: a type's parser finds its package's other
  // registries there (find_extension), as its registration function filled them.
  const ComponentRegistry* registry = nullptr;
};

// The component's task block, or a 1 kHz SCHED_FIFO 80 task when absent; a type that must be
// periodic says so (at the task block) otherwise.
TaskConfig periodic_task(const ComponentContext& ctx, const Params& params, const std::string& type);

// Exports a component's provided interface to other processes; the handle keeps it exported.
using Exporter = std::function<std::shared_ptr<void>(Component& component, const std::string& provided)>;

// One line of a run's summary for a `ColumnUse::summary` column's latest value; empty: nothing
// worth saying.
using SummaryFormat = std::function<std::string(const void* value)>;

// What a deployment can build. Each package registers its own types (its
// `register_components(ComponentRegistry&)`; a plug-in's from `saw_plugin_register`), and the
// bridge how to reach components in other processes and how to export one.
class ComponentRegistry {
 public:
  // Knows the framework's own summary columns (a device's contract, DeviceStatus).
  ComponentRegistry();

  // A type in two steps, so that a whole file is checked before anything is built:
  //   parse(const ComponentContext&, Params&) -> Config   reads `task:`/`params:`; errors name
  //                                                         file:line through Params
  //   make(const std::string& name, const Config&) -> std::unique_ptr<Component>
  // Config is a copyable value (it is kept in a DeploymentSpec).
  template <class Parse, class Make>
  void add(std::string type, std::string description, Parse parse, Make make) {
    using Config = std::decay_t<std::invoke_result_t<Parse&, const ComponentContext&, Params&>>;
    add_type(std::move(type),
             Type{std::move(description),
                  [parse](const ComponentContext& c, Params& p) { return std::any(parse(c, p)); },
                  [make](const std::string& name, const std::any& config) -> std::unique_ptr<Component> {
                    return make(name, std::any_cast<const Config&>(config));
                  },
                  {}});
  }

  struct Type {
    std::string description;
    std::function<std::any(const ComponentContext&, Params&)> parse;
    std::function<std::unique_ptr<Component>(const std::string&, const std::any&)> make;
    std::string origin;  // the plug-in that registered it; empty: built in
  };
  const Type* find(const std::string& type) const;
  const std::map<std::string, Type>& types() const noexcept { return types_; }
  // "a, b, c": for error messages.
  std::string type_list() const;

  // How a summary column of type T is reported (see ColumnUse::summary).
  template <Plain T, class F>
  void add_summary_format(F format) {
    summary_formats_[std::string(type_info_of<T>().name)] = [format](const void* v) {
      return format(*static_cast<const T*>(v));
    };
  }
  const SummaryFormat* summary_format(TypeInfo type) const;

  void add_resolver(std::function<std::unique_ptr<RemoteResolver>()> make) {
    resolvers_.push_back(std::move(make));
  }
  const std::vector<std::function<std::unique_ptr<RemoteResolver>()>>& resolvers() const noexcept {
    return resolvers_;
  }
  // A top-level deployment section a package owns (its key, e.g. "gateway"); taken already:
  // std::invalid_argument naming both origins.
  void add_section(std::string key, Section section);
  const std::map<std::string, Section>& sections() const noexcept { return sections_; }
  const Section* find_section(const std::string& key) const;

  // A registry of another kind that packages fill beside their component types (the
  // teleoperation's laws): one of each type R, made on first use and kept here, so that whatever
  // a package's registration function is given — this registry — reaches it too, with no
  // process-wide state. Copies of this registry share them.
  template <class R>
  R& extension() {
    auto& slot = extensions_[std::type_index(typeid(R))];
    if (!slot) slot = std::make_shared<R>();
    return *static_cast<R*>(slot.get());
  }
  template <class R>
  const R* find_extension() const {
    const auto it = extensions_.find(std::type_index(typeid(R)));
    return it == extensions_.end() ? nullptr : static_cast<const R*>(it->second.get());
  }

  void set_exporter(Exporter e) { exporter_ = std::move(e); }
  const Exporter& exporter() const noexcept { return exporter_; }

  // Loads a plug-in (dlopen) and runs its registration; throws std::runtime_error saying why
  // not (missing file, not a plug-in, another ABI version — naming both). A plug-in stays
  // loaded for the process's life: its code may run until the very end (destructors).
  void load_plugin(const std::string& path);
  // Off for programs that must not run code named by their input (the fuzzer).
  void allow_plugins(bool allow) noexcept { plugins_allowed_ = allow; }
  const std::vector<std::string>& plugins() const noexcept { return plugins_; }

 private:
  void add_type(std::string type, Type t);

  std::map<std::string, Type> types_;
  std::map<std::string, Section> sections_;
  std::map<std::string, std::string> section_origins_;
  std::map<std::string, SummaryFormat> summary_formats_;
  std::vector<std::function<std::unique_ptr<RemoteResolver>()>> resolvers_;
  std::map<std::type_index, std::shared_ptr<void>> extensions_;
  Exporter exporter_;
  bool plugins_allowed_ = true;
  std::vector<std::string> plugins_;  // paths loaded
  std::string loading_;               // the plug-in registering now, for Type::origin
};

}  // namespace saw::deploy
