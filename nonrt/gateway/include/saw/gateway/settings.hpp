// GatewaySettings: everything a gateway is told, declared once; the deployment's `gateway:` section.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "saw/deploy/registry.hpp"

namespace saw::gateway {

// A foreign CRTK arm (a dVRK arm) presented on this host as a component: read-only, or
// read-write for one client (a dvrk_arm device in saw-rt) when `commands` names what it may send.
struct ImportSettings {
  std::string component;  // its name here
  std::string arm;        // topics rt/[namespace/]<arm>/...
  // servo_cf (an MTM's body/servo_cf), servo_cp (a PSM's), jaw_servo_jp (its jaw/servo_jp), hold;
  // state_command comes with any.
  std::vector<std::string> commands;
  // What the import sends when its client falls silent while moving the arm, and when the
  // gateway exits: zero_wrench (servo_cf), hold, servo_cp_measured (servo_cp at the measured pose).
  std::string safe_command;
  std::int64_t command_timeout = 50'000'000;  // ns of silence from the client that count as gone
  // ns into its 1 ms cycle, on the host's common phase grid (as a task's offset): the client's
  // commands go out at the end of the import's cycle, so one placed after the client's sends
  // them in the cycle they were made in.
  std::int64_t offset = 0;
  bool operator==(const ImportSettings&) const = default;
};

// One declaration for every way a gateway is configured: a deployment's `gateway:` section (and
// what its placement on hosts implies), the one serialized form saw-rt hands saw-gateway
// (to_yaml / settings_from_yaml, the same parser), and saw-gateway's command line.
struct GatewaySettings {
  std::vector<std::string> attach;  // exported components to map (default: every export)
  // Components served by gateways on other hosts, presented on this host: NAME or NAME=LOCAL.
  std::vector<std::string> mirrors;
  std::vector<ImportSettings> imports;
  std::string ros_namespace;  // of the imported arms' topics
  // The dVRK 2.x console's pedals (sensor_msgs/Joy); "" for none.
  std::string clutch_topic = "rt/console/clutch";
  std::string operator_present_topic = "rt/console/operator_present";
  int domain = 0;
  std::vector<std::string> interfaces{"127.0.0.1"};  // loopback unless the file names others
  std::vector<std::string> peers{};  // discovery by unicast beyond this subnet (ParticipantConfig::peers)
  int decimation = 1;                // publish state every Nth row
  double display_rate =
      50;  // Hz of the states' display streams (<topic>/display); 0: none (GatewayConfig's default)
  // DDS Security: the gateway's enclave (made by `sawctl security enroll`), absolute. Off
  // loopback one is required unless the file says `security: none` (`insecure`).
  std::string enclave;
  bool insecure = false;
  std::string name;  // unique per host; "" for gateway.<pid>

  bool operator==(const GatewaySettings&) const = default;
};

// The `gateway:` section: reads it (or what placement implies without one), checks it (enclave
// files, security off loopback, attach against the exports, import names), file:line errors.
// nullopt: no gateway here.
std::optional<GatewaySettings> parse_gateway_section(deploy::SectionContext& ctx);

// The serialized form (a YAML mapping of the section's keys, fully resolved) and back, through
// the same parser as a deployment's section (without a deployment's cross-checks).
std::string to_yaml(const GatewaySettings& s);
GatewaySettings settings_from_yaml(const std::string& text, const std::string& origin);

// Starts saw-gateway (beside this program) with `s`, and waits until what it presents here
// (mirrors, imports) is in this host's bridge; the handle stops it (SIGINT) when released.
std::shared_ptr<void> launch_gateway(const GatewaySettings& s, const deploy::ComponentRegistry& registry);

// Registers the `gateway:` section (parse and, with start_processes, launch_gateway). The gateway
// package (libsawrt-gateway.so) does this in saw-rt; tests register it without processes.
void register_components(deploy::ComponentRegistry& registry, bool start_processes = true);

}  // namespace saw::gateway
