#include "saw/security/policy.hpp"

#include <ctime>
#include <sstream>
#include <stdexcept>

namespace saw::security {

namespace {

const char* schema(const char* which) {
  return which[0] == 'g' ? "http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd"
                         : "http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd";
}

std::string escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// DDS Security writes times as xsd:dateTime; UTC, as our certificates' dates.
std::string date_time(std::chrono::system_clock::time_point t) {
  const std::time_t tt = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

std::string domains(int min, int max, const char* indent) {
  std::ostringstream s;
  s << indent << "<domains>\n"
    << indent << "  <id_range><min>" << min << "</min><max>" << max << "</max></id_range>\n"
    << indent << "</domains>\n";
  return s.str();
}

void topics(std::ostringstream& s, const char* what, const std::vector<std::string>& names) {
  if (names.empty()) return;
  s << "        <" << what << ">\n          <topics>\n";
  for (const auto& n : names) s << "            <topic>" << escaped(n) << "</topic>\n";
  s << "          </topics>\n        </" << what << ">\n";
}

void validate_component(const std::string& c) {
  if (c.empty() || c.find_first_of("/*?[]\\ ") != std::string::npos)
    throw std::invalid_argument("component '" + c + "': a component name, without '/', spaces or wildcards");
}

}  // namespace

std::string_view role_name(Role r) {
  switch (r) {
    case Role::monitor:
      return "monitor";
    case Role::operator_:
      return "operator";
    case Role::gateway:
      return "gateway";
  }
  return "?";
}

Role parse_role(std::string_view name) {
  for (Role r : {Role::monitor, Role::operator_, Role::gateway})
    if (role_name(r) == name) return r;
  throw std::invalid_argument("role '" + std::string(name) + "': one of monitor, operator, gateway");
}

TopicRules topic_rules(Role role, const std::vector<std::string>& components) {
  std::vector<std::string> names = components;
  if (names.empty()) names.push_back("*");
  for (const auto& c : components) validate_component(c);
  // fnmatch without FNM_PATHNAME, as Fast DDS and Cyclone DDS match: '*' spans '/'.
  auto under = [&](const char* prefix) {
    std::vector<std::string> out;
    for (const auto& c : names) out.push_back(std::string(prefix) + c + "/*");
    return out;
  };
  auto join = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  const std::string manifest = "rt/saw/manifest";
  // ROS 2's graph topic: rmw_fastrtps and rmw_cyclonedds make a reader and a writer of it in
  // every node, so a ROS 2 node given one of our enclaves could not start without it.
  const std::string ros_graph = "ros_discovery_info";
  TopicRules t;
  switch (role) {
    case Role::monitor:
      t.subscribe = join({manifest}, under("rt/"));
      break;
    case Role::operator_:
      t.subscribe = join(join({manifest}, under("rt/")), under("rr/"));
      t.publish = join(under("rt/"), under("rq/"));
      // Commands share rt/NAME/ with state: an operator may not forge what gateways publish —
      // the registry, CRTK state and errors.
      t.deny_publish = {
          manifest,     "rt/*/measured_*", "rt/*/setpoint_*", "rt/*/goal_*", "rt/*/operating_state",
          "rt/*/error", "rt/*/warning",    "rt/*/fault"};
      break;
    case Role::gateway:
      t.publish = join(join(join({manifest}, under("rt/")), under("rq/")), under("rr/"));
      t.subscribe = t.publish;
      if (components.empty()) t.publish = t.subscribe = {"rt/*", "rq/*", "rr/*"};
      break;
  }
  t.publish.push_back(ros_graph);
  t.subscribe.push_back(ros_graph);
  return t;
}

std::string governance_xml(const GovernanceOptions& o) {
  const char* all = o.sign_only ? "SIGN" : "ENCRYPT";
  const char* data = o.sign_only ? "NONE" : "ENCRYPT";
  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xsi:noNamespaceSchemaLocation=\""
    << schema("g") << "\">\n"
    << "  <domain_access_rules>\n    <domain_rule>\n"
    << domains(o.domain_min, o.domain_max, "      ")
    << "      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>\n"
    << "      <enable_join_access_control>true</enable_join_access_control>\n"
    << "      <discovery_protection_kind>" << all << "</discovery_protection_kind>\n"
    << "      <liveliness_protection_kind>" << all << "</liveliness_protection_kind>\n"
    << "      <rtps_protection_kind>SIGN</rtps_protection_kind>\n"
    << "      <topic_access_rules>\n        <topic_rule>\n"
    << "          <topic_expression>*</topic_expression>\n"
    << "          <enable_discovery_protection>true</enable_discovery_protection>\n"
    << "          <enable_liveliness_protection>true</enable_liveliness_protection>\n"
    << "          <enable_read_access_control>true</enable_read_access_control>\n"
    << "          <enable_write_access_control>true</enable_write_access_control>\n"
    << "          <metadata_protection_kind>" << all << "</metadata_protection_kind>\n"
    << "          <data_protection_kind>" << data << "</data_protection_kind>\n"
    << "        </topic_rule>\n      </topic_access_rules>\n"
    << "    </domain_rule>\n  </domain_access_rules>\n</dds>\n";
  return s.str();
}

std::string permissions_xml(const Grant& g) {
  const TopicRules t = topic_rules(g.role, g.components);
  const std::string doms = domains(g.domain_min, g.domain_max, "        ");
  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<dds xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xsi:noNamespaceSchemaLocation=\""
    << schema("p") << "\">\n"
    << "  <permissions>\n"
    << "    <grant name=\"" << escaped(g.subject) << "\">\n"
    << "      <subject_name>" << escaped(g.subject) << "</subject_name>\n"
    << "      <validity>\n        <not_before>" << date_time(g.not_before) << "</not_before>\n"
    << "        <not_after>" << date_time(g.not_after) << "</not_after>\n      </validity>\n";
  // Rules apply in order and the first whose topics match decides. Cyclone DDS decides whether a
  // topic may be created at all by the first rule naming it in any list, so the subscriptions come
  // first (an operator must be able to read measured_cp), then the denied publications, then the
  // publications; for a writer, Fast DDS and Cyclone DDS look at the publish lists alone.
  auto rule = [&](const char* kind, const std::vector<std::string>& pub,
                  const std::vector<std::string>& sub) {
    s << "      <" << kind << ">\n" << doms;
    topics(s, "publish", pub);
    topics(s, "subscribe", sub);
    s << "      </" << kind << ">\n";
  };
  if (t.deny_publish.empty()) {
    rule("allow_rule", t.publish, t.subscribe);
  } else {
    rule("allow_rule", {}, t.subscribe);
    rule("deny_rule", t.deny_publish, {});
    rule("allow_rule", t.publish, {});
  }
  s << "      <default>DENY</default>\n"
    << "    </grant>\n  </permissions>\n</dds>\n";
  return s.str();
}

}  // namespace saw::security
