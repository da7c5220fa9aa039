// Placement: which host of a deployment file each component runs on (saw-rt --host NAME).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "saw/deploy/params.hpp"

namespace saw::deploy {

// One file describes the whole system; `hosts:` names where its parts run:
//   hosts:
//     a: {}                       # two processes of one machine: the shared-memory bridge joins them
//     b: {}
//   or
//     a: {address: 10.0.0.1}      # two machines: their gateways join them on these addresses
//     b: {address: 10.0.0.2}
// and each component says `host: a`. Without `hosts:`, everything runs here.
struct Placement {
  bool active = false;
  std::string self;                            // this process's host
  std::map<std::string, std::string> address;  // host → address ("" on this machine)
  std::map<std::string, std::string> host_of;  // component → host
  std::map<std::string, YAML::Node> entry;     // host → its entry (the keys packages' sections own)

  bool here(const std::string& component) const { return !active || host_of.at(component) == self; }
  // Another machine: its address differs from ours (both given).
  bool remote_machine(const std::string& host) const {
    return active && host != self && !address.at(host).empty() && address.at(host) != address.at(self);
  }
  std::string names() const;
};

// Reads `hosts:` and checks `host` against it (file:line errors). Components are placed as they
// are read. A host's entry may hold `section_keys` besides address: the packages' sections read them.
Placement parse_placement(const YAML::Node& root, const Params& top, const std::string& host,
                          const std::vector<std::string>& section_keys = {});

}  // namespace saw::deploy
