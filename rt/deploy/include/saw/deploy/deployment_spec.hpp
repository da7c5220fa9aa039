// DeploymentSpec: a deployment file read and checked, as a value; nothing is built or started.
#pragma once

#include <any>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "saw/deploy/config_error.hpp"
#include "saw/deploy/registry.hpp"

namespace saw::deploy {

enum class Clock : std::uint8_t { real, stepped };

// One component this host runs: its type's parsed configuration, ready for the type's make().
struct ComponentSpec {
  std::string name, type;
  std::any config;
  Location at;
};

// An interface other processes may connect to.
struct ExportSpec {
  std::string component, provided;
  Location at;
};

struct ConnectionSpec {
  std::string client, required, server, provided;
  Location at;
};

struct RecordSpec {
  std::string file;
  std::vector<std::string> columns;  // component.column
  std::vector<Location> column_at;
  int decimation = 1;
  Location at;
};

// The deployment's DDS gateway (a `gateway:` section, or implied by hosts on other machines).
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
  // DDS Security: the gateway's enclave (a directory made by `sawctl security enroll`), absolute.
  // Off loopback one is required unless the file says `security: none` (`insecure`).
  std::string enclave;
  bool insecure = false;
  Location at;
  // Mirrors or imports: connect() looks for them in this host's bridge, so the gateway starts
  // before the connections are made rather than with the tasks.
  bool before_connect() const noexcept { return !mirrors.empty() || !imports.empty(); }
};

struct DeploymentSpec {
  std::string name, file, directory;
  Clock clock = Clock::real;
  std::vector<std::string> plugins;         // loaded into the registry while parsing
  std::vector<ComponentSpec> components;    // this host's, in file order
  std::vector<ExportSpec> exports;          // the file's, then those its placement implies
  std::vector<ConnectionSpec> connections;  // those this host makes
  std::optional<GatewaySpec> gateway;
  std::optional<RecordSpec> record;
};

// Reads a deployment file and checks all of it that can be checked without building anything:
// every key, every component's parameters (by its type's parser), placement, the gateway. Loads
// the file's `plugins:` into `registry` first (their types may be named below). Throws
// ConfigError (file:line:column: key '…': what). `host`: the part of a file with `hosts:` to run.
DeploymentSpec parse_deployment(const std::string& yaml_text, const std::string& file,
                                ComponentRegistry& registry, const std::string& host = "");
DeploymentSpec load_deployment_spec(const std::string& path, ComponentRegistry& registry,
                                    const std::string& host = "");

}  // namespace saw::deploy
