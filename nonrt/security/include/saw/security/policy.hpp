// Policy: the DDS Security governance and permissions documents sawrt's keystore signs.
#pragma once

#include <chrono>
#include <string>
#include <string_view>
#include <vector>

namespace saw::security {

// What an enclave may do on the topics of sawrt (rt/NAME/..., rq/..., rr/..., rt/saw/manifest).
enum class Role {
  monitor,    // reads state, events, errors and the registry; writes nothing
  operator_,  // a monitor that also sends commands and qualified reads
  gateway,    // everything a gateway does: serves components, imports arms, mirrors other hosts
};

std::string_view role_name(Role r);
// "monitor", "operator" or "gateway"; throws std::invalid_argument naming the choices.
Role parse_role(std::string_view name);

struct GovernanceOptions {
  // Payloads signed (GMAC) but not encrypted, so a lab can read its own traffic in Wireshark;
  // discovery, liveliness and every message stay authenticated.
  bool sign_only = false;
  // Domains 0-230: Cyclone DDS 0.10 refuses governance and permissions naming 231 or 232.
  int domain_min = 0;
  int domain_max = 230;
};

struct Grant {
  std::string subject;  // the certificate's subject, e.g. CN=/gateway
  Role role = Role::monitor;
  std::chrono::system_clock::time_point not_before, not_after;
  // Component names the grant covers; empty: every component.
  std::vector<std::string> components;
  int domain_min = 0;
  int domain_max = 230;
};

// governance.xml: join access control on, unauthenticated participants refused, discovery and
// liveliness protected, every topic access-controlled and protected.
std::string governance_xml(const GovernanceOptions& options);
// permissions.xml: one grant, its rules generated from the role and the components.
std::string permissions_xml(const Grant& grant);

// The topic expressions (fnmatch patterns, as DDS Security matches them) a role may publish and
// subscribe (ROS 2's graph topic ros_discovery_info for every role, as SROS2 grants it), and those it
// is denied even where a pattern would allow them.
struct TopicRules {
  std::vector<std::string> publish, subscribe, deny_publish;
};
TopicRules topic_rules(Role role, const std::vector<std::string>& components);

}  // namespace saw::security
