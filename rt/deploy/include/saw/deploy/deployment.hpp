// Deployment: a DeploymentSpec built — components placed, exported, connected — and run.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/deploy/deployment_spec.hpp"
#include "saw/deploy/recorder.hpp"
#include "saw/deploy/registry.hpp"
#include "saw/manager.hpp"

namespace saw::deploy {

// Starts the deployment's DDS gateway process (the host's business: the RT process never runs
// DDS); the handle stops it when released. Throws std::runtime_error saying why not.
using GatewayLauncher = std::function<std::shared_ptr<void>(const GatewaySpec& spec)>;

class Deployment {
 public:
  Deployment(Deployment&&) noexcept = default;
  Deployment& operator=(Deployment&&) noexcept = default;
  ~Deployment();

  const std::string& name() const noexcept { return spec_.name; }
  const DeploymentSpec& spec() const noexcept { return spec_; }
  Clock clock() const noexcept { return spec_.clock; }
  void set_clock(Clock c) noexcept { spec_.clock = c; }
  Manager& manager() noexcept { return *manager_; }
  const std::vector<Component*>& components() const noexcept { return manager_->components(); }
  template <class T>
  T* find(const std::string& name) const {
    return dynamic_cast<T*>(manager_->find(name));
  }
  const std::optional<GatewaySpec>& gateway() const noexcept { return spec_.gateway; }
  // Overrides the file's record file (or records the file's columns somewhere else).
  void set_record_file(std::string path);

  // Starts the recorder (if any) and the manager, real or stepped per clock(), then the gateway.
  void start();
  // Stepped: advances simulated time by `seconds` as fast as possible; real: sleeps.
  void run_for(double seconds);
  void stop();
  const Recorder* recorder() const noexcept { return recorder_.get(); }

 private:
  friend Deployment build_deployment(DeploymentSpec, const ComponentRegistry&, GatewayLauncher);
  explicit Deployment(DeploymentSpec spec);
  void make_components(const ComponentRegistry& registry);
  void check_before_export(const ComponentRegistry& registry) const;
  void export_interfaces(const ComponentRegistry& registry);
  void connect_all();

  DeploymentSpec spec_;
  std::unique_ptr<Manager> manager_;
  std::unique_ptr<Recorder> recorder_;
  std::vector<std::shared_ptr<void>> exports_;  // keeps exported interfaces exported
  GatewayLauncher launch_gateway_;
  std::shared_ptr<void> gateway_process_;  // while running
};

// Builds what `spec` describes: makes each component with its type's make(), checks exports and
// record columns, exports, starts the gateway first if connections need it (mirrors, imports),
// connects. Throws ConfigError at the offending entry, having left nothing running.
Deployment build_deployment(DeploymentSpec spec, const ComponentRegistry& registry,
                            GatewayLauncher launch_gateway = {});

// parse_deployment + build_deployment.
Deployment make_deployment(const std::string& yaml_text, const std::string& file, ComponentRegistry& registry,
                           const std::string& host = "", GatewayLauncher launch_gateway = {});
Deployment load_deployment(const std::string& path, ComponentRegistry& registry, const std::string& host = "",
                           GatewayLauncher launch_gateway = {});

}  // namespace saw::deploy
