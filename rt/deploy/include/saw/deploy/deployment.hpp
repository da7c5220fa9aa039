// Deployment: a YAML file's components, tasks and connections, validated before anything starts.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/deploy/placement.hpp"
#include "saw/deploy/recorder.hpp"
#include "saw/deploy/registry.hpp"
#include "saw/manager.hpp"

namespace saw::deploy {

enum class Clock : std::uint8_t { real, stepped };

struct RecordSpec {
  std::string file;
  std::vector<std::string> columns;  // component.column
  int decimation = 1;
};

class Deployment {
 public:
  const std::string& name() const noexcept { return name_; }
  Clock clock() const noexcept { return clock_; }
  void set_clock(Clock c) noexcept { clock_ = c; }
  Manager& manager() noexcept { return *manager_; }
  const std::vector<Component*>& components() const noexcept { return manager_->components(); }
  template <class T>
  T* find(const std::string& name) const {
    return dynamic_cast<T*>(manager_->find(name));
  }
  const std::optional<RecordSpec>& record() const noexcept { return record_; }
  const std::optional<GatewaySpec>& gateway() const noexcept { return gateway_; }
  // Overrides the file's record file (or records the file's columns somewhere else).
  void set_record_file(std::string path);

  // Starts the recorder (if any) and the manager, real or stepped per clock().
  void start();
  // Stepped: advances simulated time by `seconds` as fast as possible; real: sleeps.
  void run_for(double seconds);
  void stop();
  const Recorder* recorder() const noexcept { return recorder_.get(); }

 private:
  friend Deployment parse_deployment(const std::string&, const std::string&, const ComponentRegistry&,
                                     const std::string&);
  Deployment() : manager_(std::make_unique<Manager>()) {}

  std::string name_, file_;
  Clock clock_ = Clock::real;
  std::unique_ptr<Manager> manager_;
  std::optional<RecordSpec> record_;
  std::unique_ptr<Recorder> recorder_;
  std::vector<std::shared_ptr<void>> exports_;  // keeps exported interfaces exported
  std::vector<std::string> exported_names_;
  std::map<std::string, std::string> exported_interface_;  // component → its exported interface
  std::optional<GatewaySpec> gateway_;
  GatewayLauncher launch_gateway_;
  std::shared_ptr<void> gateway_process_;  // while running
  int record_line_ = 0, record_column_ = 0;
};

// Throws ConfigError (file:line:column: key '…': what) for anything wrong, having started nothing
// (a file placed on hosts whose servers are on other machines starts its gateway first, to
// mirror them; it is stopped again on error). `host`: the part of a file with `hosts:` to run.
Deployment parse_deployment(const std::string& yaml_text, const std::string& file,
                            const ComponentRegistry& registry, const std::string& host = "");
Deployment load_deployment(const std::string& path, const ComponentRegistry& registry,
                           const std::string& host = "");

}  // namespace saw::deploy
