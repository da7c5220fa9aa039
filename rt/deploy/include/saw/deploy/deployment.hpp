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
  // A package's section (its key, e.g. "gateway"), as its parser made it; nullptr: none here.
  const SectionSpec* section(const std::string& key) const noexcept;
  // Overrides the file's record file (or records the file's columns somewhere else).
  void set_record_file(std::string path);

  // Starts the recorder (if any) and the manager, real or stepped per clock(), then the sections
  // not started yet (a gateway). A component that does not start: StartError, nothing running.
  void start();
  // Stepped: advances simulated time by `seconds` as fast as possible; real: sleeps.
  void run_for(double seconds);
  void stop();
  const Recorder* recorder() const noexcept { return recorder_.get(); }

 private:
  friend Deployment build_deployment(DeploymentSpec, const ComponentRegistry&);
  explicit Deployment(DeploymentSpec spec);
  void make_components(const ComponentRegistry& registry);
  void check_before_export(const ComponentRegistry& registry) const;
  void export_interfaces(const ComponentRegistry& registry);
  void connect_all();
  void start_sections(bool before_connect);

  DeploymentSpec spec_;
  std::unique_ptr<Manager> manager_;
  std::unique_ptr<Recorder> recorder_;
  std::vector<std::shared_ptr<void>> exports_;           // keeps exported interfaces exported
  const ComponentRegistry* registry_ = nullptr;          // outlives the deployment (its sections' starters)
  std::vector<std::shared_ptr<void>> sections_running_;  // a gateway process, while running
};

// Builds what `spec` describes: makes each component with its type's make(), checks exports and
// record columns, exports, starts the sections that present components first (a gateway's
// mirrors, imports), connects. Throws ConfigError at the offending entry, having left nothing
// running. `registry` must outlive the deployment.
Deployment build_deployment(DeploymentSpec spec, const ComponentRegistry& registry);

// parse_deployment + build_deployment.
Deployment make_deployment(const std::string& yaml_text, const std::string& file, ComponentRegistry& registry,
                           const std::string& host = "");
Deployment load_deployment(const std::string& path, ComponentRegistry& registry,
                           const std::string& host = "");

}  // namespace saw::deploy
