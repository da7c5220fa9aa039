// The `gateway:` section: read, checked, and serialized for saw-gateway by the same code.
#include "saw/gateway/settings.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>

namespace saw::gateway {
namespace {

using deploy::ConfigError;
using deploy::Params;

std::string relative_to(const std::string& directory, const std::string& path) {
  std::filesystem::path p(path);
  if (p.is_relative() && !directory.empty()) p = std::filesystem::path(directory) / p;
  return p.lexically_normal().string();
}

void add_unique(std::vector<std::string>& v, const std::string& x) {
  if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
}

// An enclave as `sawctl security enroll` makes it (SROS2's layout): checked here so that a wrong
// path is a file:line error, not a gateway failing after the RT tasks started.
void check_enclave(const Params& p, const std::string& key, const std::string& dir) {
  for (const char* f : {"cert.pem", "key.pem", "identity_ca.cert.pem", "permissions_ca.cert.pem",
                        "governance.p7s", "permissions.p7s"})
    if (std::error_code ec; !std::filesystem::exists(std::filesystem::path(dir) / f, ec))
      p.fail_at(key, "enclave " + dir + " has no " + f +
                         " (make one with: sawctl security enroll KEYSTORE NAME --role gateway)");
}

// A read-write import's keys: what its client may send the arm, and what the import sends when
// that client falls silent or the gateway exits.
void read_import_commands(const Params& im, ImportSettings& s) {
  using namespace std::chrono_literals;
  s.commands = im.get_or<std::vector<std::string>>("commands", {});
  const auto allowed = [&](const std::string& c) {
    return std::find(s.commands.begin(), s.commands.end(), c) != s.commands.end();
  };
  static const std::vector<std::string> known{"servo_cf", "servo_cp", "servo_jp", "jaw_servo_jp",
                                              "move_cp",  "move_jp",  "hold",     "free"};
  for (const auto& c : s.commands)
    if (std::find(known.begin(), known.end(), c) == known.end())
      im.fail_at("commands",
                 "'" + c +
                     "' is not one of: servo_cf (an MTM), servo_cp (a PSM), servo_jp, jaw_servo_jp (its "
                     "jaw), move_cp, move_jp, hold, free");
  if (allowed("servo_cf") && allowed("servo_cp"))
    im.fail_at("commands", "servo_cf (an MTM's wrench) or servo_cp (a PSM's pose), not both");
  if (s.commands.empty()) {
    for (const char* k : {"safe_command", "command_timeout", "offset"})
      if (im.has(k)) im.fail_at(k, "only for an import that sends commands (commands: [...])");
    return;
  }
  const char* fallback = allowed("servo_cf") ? "zero_wrench" : allowed("hold") ? "hold" : "servo_cp_measured";
  s.safe_command = im.get_or<std::string>("safe_command", fallback);
  const std::string needs = s.safe_command == "zero_wrench"         ? "servo_cf"
                            : s.safe_command == "hold"              ? "hold"
                            : s.safe_command == "servo_cp_measured" ? "servo_cp"
                                                                    : "";
  if (needs.empty())
    im.fail_at("safe_command",
               "'" + s.safe_command + "' is not one of: zero_wrench, hold, servo_cp_measured");
  if (!allowed(needs)) im.fail_at("safe_command", s.safe_command + " needs " + needs + " in commands");
  s.command_timeout =
      im.get_duration_in("command_timeout", std::chrono::nanoseconds(s.command_timeout), 2ms, 1s);
  s.offset =
      im.get_duration_in("offset", 0ns, 0ns, 999us, "at least 0 and less than the import's 1 ms period");
}

// Every key of the section; `exported` (a deployment's) is the default of attach.
void read_keys(Params& g, const YAML::Node& node, const std::string& directory,
               const std::vector<std::string>& exported, GatewaySettings& gw) {
  gw.attach = g.get_or<std::vector<std::string>>("attach", exported);
  gw.mirrors = g.get_or<std::vector<std::string>>("mirror", {});
  // The da Vinci stream: foreign CRTK arms presented here (rt/[namespace/]<arm>/measured_cp, ...).
  if (g.has("import")) {
    g.mark_used("import");
    const YAML::Node list = node["import"];
    if (!list.IsSequence()) g.fail_at("import", "expected a list of {component, arm}");
    for (std::size_t i = 0; i < list.size(); ++i) {
      Params im(list[i], g.file(), g.path() + ".import[" + std::to_string(i) + "]");
      ImportSettings s;
      s.component = im.get<std::string>("component");
      s.arm = im.get_or<std::string>("arm", s.component);
      read_import_commands(im, s);
      im.check_all_used();
      gw.imports.push_back(s);
    }
  }
  gw.ros_namespace = g.get_or<std::string>("namespace", "");
  gw.clutch_topic = g.get_or<std::string>("clutch_topic", gw.clutch_topic);
  gw.operator_present_topic = g.get_or<std::string>("operator_present_topic", gw.operator_present_topic);
  gw.domain = static_cast<int>(g.get_in_range("domain", 0, 232, 0));
  if (g.has("domain") && g.get<double>("domain") != gw.domain) g.fail_at("domain", "expected an integer");
  gw.interfaces = g.get_or<std::vector<std::string>>("interfaces", gw.interfaces);
  if (gw.interfaces.empty()) g.fail_at("interfaces", "at least one interface address");
  gw.peers = g.get_or<std::vector<std::string>>("peers", {});
  if (!gw.peers.empty() && gw.interfaces == std::vector<std::string>{"127.0.0.1"})
    g.fail_at("peers", "DDS uses loopback only: name the interface that reaches them (interfaces:)");
  gw.decimation = static_cast<int>(g.get_in_range("decimation", 1, 1000, 1));
  gw.display_rate = g.get_in_range("display_rate", 0, 1000, gw.display_rate);
  gw.name = g.get_or<std::string>("name", "");
  if (g.has("enclave")) {
    gw.enclave = relative_to(directory, g.get<std::string>("enclave"));
    check_enclave(g, "enclave", gw.enclave);
  }
  if (g.has("security")) {
    const auto mode = g.get<std::string>("security");
    if (mode != "none")
      g.fail_at("security", "'" + mode +
                                "': the only value is none (to run without DDS Security); for security "
                                "give enclave:");
    if (g.has("enclave")) g.fail_at("security", "security: none and an enclave: choose one");
    gw.insecure = true;
  }
}

// Off this machine's loopback, a gateway without DDS Security lets anyone on that network read
// the robot and command it: refused unless the file says `security: none` (saw-rt then warns).
void check_security(const GatewaySettings& gw, const deploy::Location& at) {
  const bool off_loopback = std::any_of(gw.interfaces.begin(), gw.interfaces.end(),
                                        [](const std::string& a) { return !a.starts_with("127."); });
  if (off_loopback && gw.enclave.empty() && !gw.insecure)
    throw ConfigError(at,
                      "the gateway's DDS leaves loopback and no security is configured: give its enclave "
                      "(enclave: KEYSTORE/enclaves/NAME, see docs/security.md) or say security: none");
}

}  // namespace

std::optional<GatewaySettings> parse_gateway_section(deploy::SectionContext& ctx) {
  const bool implied = !ctx.remote_clients.empty() || !ctx.remote_servers.empty();
  if (!ctx.params && !implied) return std::nullopt;
  GatewaySettings gw;
  bool interfaces_named = false;
  if (ctx.params) {
    Params& g = *ctx.params;
    read_keys(g, ctx.node, ctx.directory, ctx.exported, gw);
    interfaces_named = g.has("interfaces");
    for (const auto& a : gw.attach)
      if (std::find(ctx.exported.begin(), ctx.exported.end(), a) == ctx.exported.end())
        g.fail_at("attach", "'" + a + "' is not exported by this deployment (see exports:)");
    for (const auto& im : gw.imports)
      if (ctx.is_component && ctx.is_component(im.component))
        g.fail_at("import", "a component named '" + im.component + "' exists already");
    if (gw.attach.empty() && gw.imports.empty() && gw.mirrors.empty() && !implied)
      g.fail("nothing to map: this deployment exports no interface (see exports:)");
  } else {
    gw.attach.clear();
  }
  // Placed on hosts of other machines: what crosses is attached here, what is used from there
  // mirrored here, on this host's address and with this host's own enclave.
  for (const auto& a : ctx.remote_clients) add_unique(gw.attach, a);
  for (const auto& m : ctx.remote_servers) add_unique(gw.mirrors, m);
  if (implied && !interfaces_named && !ctx.address.empty()) gw.interfaces = {ctx.address};
  if (ctx.host_entry && ctx.host_entry->has("enclave")) {
    if (gw.insecure)
      ctx.host_entry->fail_at("enclave", "gateway: says security: none; a host's enclave contradicts it");
    gw.enclave = relative_to(ctx.directory, ctx.host_entry->get<std::string>("enclave"));
    check_enclave(*ctx.host_entry, "enclave", gw.enclave);
  }
  check_security(gw, ctx.at);
  return gw;
}

std::string to_yaml(const GatewaySettings& s) {
  YAML::Emitter out;
  out << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "attach" << YAML::Value << s.attach;
  out << YAML::Key << "mirror" << YAML::Value << s.mirrors;
  if (!s.imports.empty()) {
    out << YAML::Key << "import" << YAML::Value << YAML::BeginSeq;
    for (const auto& im : s.imports) {
      out << YAML::BeginMap << YAML::Key << "component" << YAML::Value << im.component << YAML::Key << "arm"
          << YAML::Value << im.arm;
      if (!im.commands.empty())
        out << YAML::Key << "commands" << YAML::Value << im.commands << YAML::Key << "safe_command"
            << YAML::Value << im.safe_command << YAML::Key << "command_timeout" << YAML::Value
            << (std::to_string(im.command_timeout) + "ns") << YAML::Key << "offset" << YAML::Value
            << (std::to_string(im.offset) + "ns");
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  out << YAML::Key << "namespace" << YAML::Value << s.ros_namespace;
  out << YAML::Key << "clutch_topic" << YAML::Value << s.clutch_topic;
  out << YAML::Key << "operator_present_topic" << YAML::Value << s.operator_present_topic;
  out << YAML::Key << "domain" << YAML::Value << s.domain;
  out << YAML::Key << "interfaces" << YAML::Value << s.interfaces;
  if (!s.peers.empty()) out << YAML::Key << "peers" << YAML::Value << s.peers;
  out << YAML::Key << "decimation" << YAML::Value << s.decimation;
  out << YAML::Key << "display_rate" << YAML::Value << s.display_rate;
  if (!s.name.empty()) out << YAML::Key << "name" << YAML::Value << s.name;
  if (!s.enclave.empty()) out << YAML::Key << "enclave" << YAML::Value << s.enclave;
  if (s.insecure) out << YAML::Key << "security" << YAML::Value << "none";
  out << YAML::EndMap;
  return out.c_str();
}

GatewaySettings settings_from_yaml(const std::string& text, const std::string& origin) {
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(origin, e.mark.line + 1, e.mark.column + 1, "", "YAML syntax: " + e.msg);
  }
  if (!node.IsMap()) throw ConfigError(origin, 0, 0, "", "expected the gateway's settings as a mapping");
  Params g(node, origin, "");
  GatewaySettings gw;
  read_keys(g, node, "", {}, gw);
  g.check_all_used();
  check_security(gw, {origin, 0, 0, ""});
  return gw;
}

void register_components(deploy::ComponentRegistry& registry, bool start_processes) {
  deploy::Section section;
  section.description = "the DDS gateway of this host (saw-gateway): exports, mirrors, imports, security";
  section.host_keys = {"enclave"};
  section.parse = [](deploy::SectionContext& ctx) -> std::optional<deploy::SectionValue> {
    auto gw = parse_gateway_section(ctx);
    if (!gw) return std::nullopt;
    deploy::SectionValue v;
    // Mirrors and imports: connect() looks for them in this host's bridge.
    v.before_connect = !gw->mirrors.empty() || !gw->imports.empty();
    for (const auto& im : gw->imports) v.presents.push_back(im.component);
    v.value = std::move(*gw);
    return v;
  };
  if (start_processes)
    section.start = [](const std::any& value, const deploy::ComponentRegistry& r) {
      return launch_gateway(std::any_cast<const GatewaySettings&>(value), r);
    };
  registry.add_section("gateway", std::move(section));
}

}  // namespace saw::gateway
