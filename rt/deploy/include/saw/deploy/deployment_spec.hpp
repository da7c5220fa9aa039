// DeploymentSpec: a deployment file read and checked, as a value; nothing is built or started.
#pragma once

#include <any>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "saw/deploy/config_error.hpp"
#include "saw/deploy/registry.hpp"
#include "saw/deploy/section.hpp"

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

struct DeploymentSpec {
  std::string name, file, directory;
  Clock clock = Clock::real;
  std::vector<std::string> plugins;         // loaded into the registry while parsing
  std::vector<ComponentSpec> components;    // this host's, in file order
  std::vector<ExportSpec> exports;          // the file's, then those its placement implies
  std::vector<ConnectionSpec> connections;  // those this host makes
  std::vector<SectionSpec> sections;        // the packages' sections (gateway:), parsed by their owners
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
