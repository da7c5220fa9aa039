// ComponentRegistry: the component types a deployment file may name, and how to build each.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/component.hpp"
#include "saw/deploy/params.hpp"
#include "saw/manager.hpp"
#include "saw/task.hpp"

namespace saw::deploy {

// What a factory gets: the component's name, its task block (absent → the type's default),
// its parameters, and the directory of the deployment file (for relative paths).
struct FactoryContext {
  std::string name;
  std::optional<TaskConfig> task;
  Params& params;
  std::string directory;
};

using Factory = std::function<std::unique_ptr<Component>(FactoryContext&)>;

// Exports a component's provided interface to other processes; the handle keeps it exported.
using Exporter = std::function<std::shared_ptr<void>(Component& component, const std::string& provided)>;

// The deployment's DDS gateway (a `gateway:` section): what to map and where.
struct GatewaySpec {
  std::vector<std::string> attach;  // exported components to map (default: every export)
  int domain = 0;
  std::vector<std::string> interfaces{"127.0.0.1"};  // loopback unless the file names others
  int decimation = 1;
  std::vector<std::string> mirrors;  // components of other machines to present here (started before connect)
  // Foreign CRTK arms (a dVRK's masters) to present here as components, read-only: component
  // name → arm name; topics rt/[ros_namespace/]<arm>/... (started before connect).
  std::vector<std::pair<std::string, std::string>> imports;
  std::string ros_namespace;
};
// Starts the gateway process for a running deployment; the handle stops it when released.
using GatewayLauncher = std::function<std::shared_ptr<void>(const GatewaySpec& spec)>;

// What a deployment can build: component types, plus (from the composition root, so that this
// library depends on neither) how to reach components elsewhere and how to export one.
class ComponentRegistry {
 public:
  void add(std::string type, Factory factory, std::string description);
  void add_resolver(std::function<std::unique_ptr<RemoteResolver>()> make) {
    resolvers_.push_back(std::move(make));
  }
  void set_exporter(Exporter e) { exporter_ = std::move(e); }
  void set_gateway_launcher(GatewayLauncher l) { gateway_launcher_ = std::move(l); }
  const GatewayLauncher& gateway_launcher() const noexcept { return gateway_launcher_; }
  const std::vector<std::function<std::unique_ptr<RemoteResolver>()>>& resolvers() const noexcept {
    return resolvers_;
  }
  const Exporter& exporter() const noexcept { return exporter_; }
  const Factory* find(const std::string& type) const;
  // "a, b, c": for error messages.
  std::string type_list() const;
  const std::map<std::string, std::pair<Factory, std::string>>& types() const noexcept { return types_; }

 private:
  std::map<std::string, std::pair<Factory, std::string>> types_;
  std::vector<std::function<std::unique_ptr<RemoteResolver>()>> resolvers_;
  Exporter exporter_;
  GatewayLauncher gateway_launcher_;
};

}  // namespace saw::deploy
