// A deployment section a package owns (a `gateway:`): its parser and what starts it.
#pragma once

#include <any>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/deploy/config_error.hpp"
#include "saw/deploy/params.hpp"

namespace saw::deploy {

class ComponentRegistry;

// What a section's parser gets: its own mapping when the file has one, and what the deployment
// says about this host that the section may need (its placement, what crosses to other hosts).
struct SectionContext {
  std::optional<Params> params;  // the section's mapping; nullopt: not in the file (placement may imply it)
  YAML::Node node;               // the same, raw (lists of mappings), or undefined
  Location at;                   // the section's key (or hosts:, when only implied)
  std::string file, directory;
  // Placement (a file with `hosts:`; empty otherwise).
  std::string host;                         // this process's host
  std::string address;                      // its address; "" on this machine
  std::optional<Params> host_entry;         // this host's entry of hosts:, for the keys the section owns
  std::vector<std::string> exported;        // components this host exports (exports:, and placement's)
  std::vector<std::string> remote_clients;  // exported components used by components on other machines
  std::vector<std::string> remote_servers;  // components of other machines used here
  std::function<bool(const std::string&)> is_component;  // named by components: (any host)
};

// What the section came to: a value for its starter, and what the deployment must know of it.
struct SectionValue {
  std::any value;
  // Start it before the connections are made (it presents components they name).
  bool before_connect = false;
  // Components it presents on this host that components: does not list (connections may name them).
  std::vector<std::string> presents;
};

struct Section {
  std::string description;
  // The keys of a hosts: entry this section owns (a host's own settings for it).
  std::vector<std::string> host_keys;
  // Reads the section (errors name file:line through Params); nullopt: nothing to do here.
  std::function<std::optional<SectionValue>(SectionContext&)> parse;
  // Starts what it describes once the components are built (a process); the handle stops it when
  // released. Throws std::runtime_error saying why not.
  std::function<std::shared_ptr<void>(const std::any& value, const ComponentRegistry& registry)> start;
};

// A parsed section of a DeploymentSpec.
struct SectionSpec {
  std::string key;
  SectionValue value;
  Location at;
};

}  // namespace saw::deploy
