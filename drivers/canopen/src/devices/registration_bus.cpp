// The CANopen types of a shared bus for deployments: canopen_bus (the bus task) and canopen_io (an I/O node).
#include "registration_bus.hpp"

#include <chrono>
#include <cstdio>

#include "saw/canopen/canopen_bus.hpp"
#include "saw/canopen/canopen_io.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/device_params.hpp"
#include "saw/canopen/eds.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/pdo_text.hpp"
#include "saw/deploy/device_settings.hpp"

namespace saw::canopen {
namespace {

using namespace std::chrono_literals;
using deploy::ComponentContext;
using deploy::Params;

struct BusSpec {
  TaskConfig task;
  CanopenBusConfig config;
};

BusSpec parse_bus_task(const ComponentContext& ctx, Params& p) {
  BusSpec s;
  s.config.uri = p.get<std::string>("bus");
  if (!is_bus_uri(s.config.uri))
    p.fail_at("bus", "'" + s.config.uri + "' is not a bus: virtual:<name> or socketcan:<interface>");
  s.task = deploy::periodic_task(ctx, p, "canopen_bus");
  const MasterHeartbeatParams master = params::parse_master_heartbeat(p);
  s.config.node = master.node;
  s.config.heartbeat_period = master.period;
  s.config.heartbeat_timeout = master.timeout;
  // The send phase: after the route phase (the task's offset) with room for the clients between
  // (at least 1 us each side), within the period.
  const TimeNs period = s.task.period.count(), route = s.task.offset.count();
  if (p.has("sync_offset")) {
    s.config.sync_offset = p.get<std::chrono::nanoseconds>("sync_offset").count();
    if (s.config.sync_offset < route + 2'000 || s.config.sync_offset >= period)
      p.fail_at("sync_offset", "must be at least 2 us after the task's offset (" +
                                   std::to_string(route / 1000) +
                                   " us: the route phase; the clients run between) and below the period (" +
                                   std::to_string(period / 1000) + " us)");
  } else if (period - route < 4'000) {
    p.fail(
        "task.offset leaves no room for the send phase and the clients before the period's end (give "
        "sync_offset, or an earlier offset)");
  }
  return s;
}

struct IoSpec {
  TaskConfig task;
  CanopenIoConfig config;
};

std::optional<PdoEntry> entry(const Params& p, const std::string& key) {
  if (!p.has(key)) return std::nullopt;
  try {
    return parse_pdo_entry(p.get<std::string>(key));
  } catch (const std::invalid_argument& e) {
    p.fail_at(key, e.what());
  }
}

// `channels: [jaw]` and each under `joints: jaw: {output, input, scale, offset, min, max, ...}`.
IoChannel parse_channel(const Params& joints, const std::string& name) {
  if (!joints.has(name)) joints.fail_at(name, "channels names '" + name + "': give its parameters here");
  const Params j = joints.child(name);
  IoChannel ch;
  ch.name = name;
  if (name.size() > JointState::max_name) j.fail("a channel's name has at most 31 characters");
  ch.output = entry(j, "output");
  if (!ch.output)
    j.fail_at("output", "required parameter is missing (the RPDO-mapped object, 0x6411:01:i16)");
  ch.input = entry(j, "input");
  ch.scale = j.get_in_range("scale", -1e9, 1e9, 1);
  if (ch.scale == 0) j.fail_at("scale", "must not be 0");
  ch.offset = j.get_in_range("offset", -1e9, 1e9, 0);
  ch.min = j.get<double>("min");
  ch.max = j.get<double>("max");
  if (!(ch.min < ch.max)) j.fail_at("max", "must be above min");
  ch.max_velocity = j.get_in_range("max_velocity", 1e-9, 1e9, 1e9);
  ch.safe = j.get_in_range("safe", ch.min, ch.max, std::clamp(0.0, ch.min, ch.max));
  ch.error_value = j.get_or<bool>("error_value", true);
  return ch;
}

// The PDOs when the file gives neither `pdo` nor `eds`: RPDO1 the outputs, TPDO1 the inputs,
// 2..4 not valid.
std::vector<PdoMapping> default_io_pdos(const Params& p, std::uint8_t node,
                                        const std::vector<PdoEntry>& outputs,
                                        const std::vector<PdoEntry>& inputs) {
  std::vector<PdoMapping> pdos;
  for (const PdoKind kind : {PdoKind::rpdo, PdoKind::tpdo})
    for (std::uint16_t n = 1; n <= 4; ++n) {
      const auto& entries = kind == PdoKind::rpdo ? outputs : inputs;
      if (n == 1 && !entries.empty()) {
        try {
          pdos.push_back(make_pdo(kind, n, node, entries));
        } catch (const std::invalid_argument& e) {
          p.fail_at("channels", e.what());
        }
        continue;
      }
      pdos.push_back(unused_pdo(kind, n, node));
    }
  return pdos;
}

IoSpec parse_io(const ComponentContext& ctx, Params& p) {
  IoSpec s;
  CanopenIoConfig& c = s.config;
  s.task = deploy::periodic_task(ctx, p, "canopen_io");
  const NodeParams n = params::parse_node(p, s.task.period.count());
  apply_node_params(n, c);
  c.interface_name = p.get_or<std::string>("interface", "io");
  const int node = p.get<int>("node");
  if (!valid_node_id(static_cast<unsigned>(node))) p.fail_at("node", "a node-ID is 1..127");
  c.node.node = static_cast<std::uint8_t>(node);
  c.node.name = ctx.name;
  c.node.heartbeat_period = n.heartbeat_period;
  c.node.heartbeat_timeout = n.heartbeat_timeout;
  const auto names = p.get<std::vector<std::string>>("channels");
  if (names.empty() || names.size() > JointState::max_joints) p.fail_at("channels", "1 to 8 channels");
  const Params joints = p.child("joints");
  for (const std::string& name : names) {
    c.channels.push_back(parse_channel(joints, name));
    c.node.outputs.push_back(*c.channels.back().output);
    if (c.channels.back().input) c.node.inputs.push_back(*c.channels.back().input);
  }
  if (p.has("pdo") || p.has("eds")) {
    std::optional<DriveIdentity> identity;
    // The EDS also types the CiA 401 error objects (c.eds).
    c.node.pdos = params::parse_pdos(p, cia402::csp, c.node.node, ctx.directory, identity, &c.eds);
    c.node.identity = identity;
  } else {
    p.mark_used("pdo");
    c.node.pdos = default_io_pdos(p, c.node.node, c.node.outputs, c.node.inputs);
  }
  c.node.writes = params::parse_writes(p);
  c.contract = deploy::parse_device_settings(p, s.task, {.force = false}, c.contract);
  try {
    check(c.node);
  } catch (const std::invalid_argument& e) {
    p.fail(e.what());
  }
  return s;
}

std::string bus_line(const CanopenBusStatus& s) {
  char b[400];
  std::snprintf(
      b, sizeof b,
      "bus %s, %u components, master node %u: %llu SYNC, %llu heartbeats, %llu frames received, %llu "
      "sent (%llu refused), %llu for no component, %llu dropped (a component's queue full), %llu phases "
      "skipped (the other still ran)",
      std::string(can::to_string(static_cast<can::BusState>(s.bus_state))).c_str(), s.clients, s.node,
      static_cast<unsigned long long>(s.syncs), static_cast<unsigned long long>(s.heartbeats),
      static_cast<unsigned long long>(s.frames_received), static_cast<unsigned long long>(s.frames_sent),
      static_cast<unsigned long long>(s.send_refused), static_cast<unsigned long long>(s.foreign_frames),
      static_cast<unsigned long long>(s.dropped), static_cast<unsigned long long>(s.phase_skips));
  return b;
}

std::string io_line(const CanopenIoStatus& s) {
  char b[320];
  std::snprintf(b, sizeof b,
                "%s, node %u %s, bus %s: %llu EMCY, %u heartbeat losses, %u boot-ups (%llu configured "
                "again), %llu bad PDOs",
                std::string(to_string(s.state)).c_str(), s.node,
                std::string(to_string(static_cast<NmtState>(s.nmt_state))).c_str(),
                std::string(can::to_string(static_cast<can::BusState>(s.bus_state))).c_str(),
                static_cast<unsigned long long>(s.emcy), s.heartbeat_losses, s.boot_ups,
                static_cast<unsigned long long>(s.reconfigurations),
                static_cast<unsigned long long>(s.bad_pdos));
  std::string out = b;
  if (s.emcy != 0) {
    std::snprintf(b, sizeof b, "; the last EMCY 0x%04X (%s), error register 0x%02X", s.last_emcy,
                  std::string(emcy_name(s.last_emcy)).c_str(), s.error_register);
    out += b;
  }
  if (s.warnings != 0) {
    std::snprintf(b, sizeof b, "; %llu warning EMCY, the last 0x%04X (%s), error register 0x%02X",
                  static_cast<unsigned long long>(s.warnings), s.last_warning,
                  std::string(emcy_name(s.last_warning)).c_str(), s.last_warning_register);
    out += b;
  }
  return out;
}

}  // namespace

void register_bus_components(deploy::ComponentRegistry& registry) {
  registry.add("canopen_bus",
               "the bus task of one CAN bus that CANopen components share (SYNC, the master's heartbeat; "
               "`bus: <its name>`)",
               parse_bus_task, [](const std::string& name, const BusSpec& s) {
                 return std::make_unique<CanopenBus>(name, s.task, s.config);
               });
  registry.add("canopen_io", "a generic CANopen I/O node (its PDO-mapped objects) as CRTK joints (servo_jp)",
               parse_io, [](const std::string& name, const IoSpec& s) {
                 return std::make_unique<CanopenIo>(name, client_task(s.config.bus, name, s.task), s.config);
               });
  registry.add_summary_format<CanopenBusStatus>(bus_line);
  registry.add_summary_format<CanopenIoStatus>(io_line);
}

}  // namespace saw::canopen
