// The CANopen types for deployments: each parameter read, range-checked and located (file:line:key).
#include "saw/canopen/registration.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "registration_bus.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/canopen/canopen_arm.hpp"
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

using params::parse_pdos;
using params::parse_writes;

struct CanopenSpec {
  TaskConfig task;
  CanopenArmConfig config;
};

cia402::Mode parse_mode(const Params& p) {
  return p.get_enum<cia402::Mode>("mode", {{"csp", cia402::csp}, {"csv", cia402::csv}, {"cst", cia402::cst}},
                                  cia402::csp);
}

// A joint's drive: node, units, limits, and (arm) its place in the chain.
JointConfig parse_joint(const Params& j, const std::string& name, cia402::Mode mode, const Params& shared,
                        const std::string& directory, ChainJoint* kinematics) {
  JointConfig c;
  c.name = name;
  if (name.size() > JointState::max_name) j.fail("a joint's name has at most 31 characters");
  const int node = j.get<int>("node");
  if (!valid_node_id(static_cast<unsigned>(node))) j.fail_at("node", "a node-ID is 1..127");
  c.node = static_cast<std::uint8_t>(node);
  const auto type = j.get_enum<ChainJoint::Type>(
      "type", {{"revolute", ChainJoint::Type::revolute}, {"prismatic", ChainJoint::Type::prismatic}},
      ChainJoint::Type::revolute);
  const double counts = j.get_in_range("counts_per_revolution", 1, 1e9, 0);
  if (counts == 0) j.fail_at("counts_per_revolution", "required parameter is missing");
  const double gear = j.get_in_range("gear_ratio", 1e-6, 1e6, 1);
  const double rated = j.get_in_range("rated_torque", 1e-6, 1e4, 0);
  if (rated == 0)
    j.fail_at("rated_torque", "required parameter is missing (the motor's, N·m: 0x6076 / 1000)");
  if (type == ChainJoint::Type::prismatic) {
    const double lead = j.get_in_range("lead", 1e-6, 10, 0);
    if (lead == 0) j.fail_at("lead", "a prismatic joint needs its lead (m of travel per output revolution)");
    c.units = DriveUnits::linear(counts, gear, lead, rated);
  } else {
    c.units = DriveUnits::rotary(counts, gear, rated);
  }
  c.min = j.get<double>("min");
  c.max = j.get<double>("max");
  if (!(c.min < c.max)) j.fail_at("max", "must be above min");
  c.max_velocity = j.get_in_range("max_velocity", 1e-6, 1e4, 1);
  c.max_torque = j.get_in_range("max_torque", 0, 1e5, 0);
  c.following_error = j.get_in_range("following_error", 0, 1e3, 0);
  c.offset = j.get_in_range("offset", -1e6, 1e6, 0);
  const bool own_pdos = j.has("pdo") || j.has("eds");
  std::optional<Eds> eds;
  c.pdos = parse_pdos(own_pdos ? j : shared, mode, c.node, directory, c.identity, &eds);
  if (eds) c.rpdo_deadline_unwritable = rpdos_without_event_timer(*eds, c.pdos);
  c.writes = parse_writes(shared);
  if (&j != &shared)
    for (const SdoWrite& w : parse_writes(j)) c.writes.push_back(w);
  if (kinematics != nullptr) {
    kinematics->type = type;
    kinematics->xyz = j.get_or<Vec3>("xyz", {0, 0, 0});
    kinematics->rpy = j.get_or<Vec3>("rpy", {0, 0, 0});
    kinematics->axis = j.get_or<Vec3>("axis", {0, 0, 1});
    const auto& a = kinematics->axis;
    if (!(std::hypot(a[0], a[1], a[2]) > 1e-9)) j.fail_at("axis", "must be a non-zero direction");
  }
  return c;
}

// What both types share: the bus, the mode, heartbeats, timeouts, the start-up.
void parse_common(const ComponentContext& ctx, Params& p, const std::string& type, CanopenSpec& s) {
  CanopenArmConfig& c = s.config;
  c.mode = parse_mode(p);
  s.task = deploy::periodic_task(ctx, p, type);
  const NodeParams n = params::parse_node(p, s.task.period.count());
  apply_node_params(n, c);
  c.heartbeat_period = n.heartbeat_period;
  c.heartbeat_timeout = n.heartbeat_timeout;
  c.abort_connection = p.get_enum<AbortConnection>("abort_connection",
                                                   {{"none", AbortConnection::none},
                                                    {"fault", AbortConnection::fault},
                                                    {"disable_voltage", AbortConnection::disable_voltage},
                                                    {"quick_stop", AbortConnection::quick_stop}},
                                                   AbortConnection::quick_stop);
  c.contract = deploy::parse_device_settings(p, s.task, {.force = p.has("chain"), .enable_timeout = false},
                                             c.contract);
  c.transition_timeout = p.get_duration_in("transition_timeout", 1s, 10ms, 60s);
}

// The checks that need the whole configuration (the drives' PDO maps against the mode, shared
// node-IDs): at the parameters' mapping.
void check_all(const Params& p, CanopenSpec& s) {
  try {
    s.config = checked(std::move(s.config), s.task);
  } catch (const std::invalid_argument& e) {
    p.fail(e.what());
  }
}

CanopenSpec parse_drive(const ComponentContext& ctx, Params& p) {
  CanopenSpec s;
  parse_common(ctx, p, "canopen_drive", s);
  s.config.interface_name = "drive";
  const std::string joint = p.get_or<std::string>("joint", ctx.name);
  s.config.joints.push_back(parse_joint(p, joint, s.config.mode, p, ctx.directory, nullptr));
  check_all(p, s);
  return s;
}

CanopenSpec parse_arm(const ComponentContext& ctx, Params& p) {
  CanopenSpec s;
  parse_common(ctx, p, "canopen_arm", s);
  const auto names = p.get<std::vector<std::string>>("chain");
  if (names.empty() || names.size() > JointState::max_joints)
    p.fail_at("chain", "an arm has 1 to 8 joints, base to tip");
  const Params joints = p.child("joints");
  ChainSpec chain;
  for (const std::string& name : names) {
    if (!joints.has(name))
      joints.fail_at(name, "the chain names joint '" + name + "': give its parameters here");
    if (std::count(names.begin(), names.end(), name) > 1) p.fail_at("chain", "joint '" + name + "' twice");
    ChainJoint& k = chain.joints.emplace_back();
    s.config.joints.push_back(parse_joint(joints.child(name), name, s.config.mode, p, ctx.directory, &k));
  }
  const Params tip = p.child("tip");
  chain.tip_xyz = tip.get_or<Vec3>("xyz", {0, 0, 0});
  chain.tip_rpy = tip.get_or<Vec3>("rpy", {0, 0, 0});
  s.config.chain = chain;
  check_all(p, s);
  return s;
}

std::string hex(std::uint16_t v) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%04X", v);
  return b;
}

std::string summary_line(const CanopenStatus& s) {
  char b[512];
  std::string out;
  const std::string state(to_string(s.state)), bus(can::to_string(static_cast<can::BusState>(s.bus_state)));
  if (s.shared_bus != 0)  // SYNC and the master's heartbeat are its bus task's (its own summary line)
    std::snprintf(
        b, sizeof b,
        "%s, bus %s (a client of its bus task): %llu frames received, %llu sent (%llu refused), %llu "
        "for others",
        state.c_str(), bus.c_str(), static_cast<unsigned long long>(s.frames_received),
        static_cast<unsigned long long>(s.frames_sent), static_cast<unsigned long long>(s.send_refused),
        static_cast<unsigned long long>(s.foreign_frames));
  else
    std::snprintf(
        b, sizeof b, "%s, bus %s: %llu SYNC, %llu frames received, %llu sent (%llu refused), %llu for others",
        state.c_str(), bus.c_str(), static_cast<unsigned long long>(s.syncs),
        static_cast<unsigned long long>(s.frames_received), static_cast<unsigned long long>(s.frames_sent),
        static_cast<unsigned long long>(s.send_refused), static_cast<unsigned long long>(s.foreign_frames));
  out += b;
  if (s.faults != 0 && s.fault.code == FaultCode::deadline_missed) {
    // The base's fault, not the drives': its own words say it all.
    out += "\n" + std::to_string(s.faults) + " faults; the last: " + saw::to_string(s.fault);
  } else if (s.faults != 0) {
    const FaultReason reason = s.fault.code == FaultCode::none ? FaultReason::none : s.reason;
    char node[16] = "";
    if (s.fault_node != 0) std::snprintf(node, sizeof node, " (node %u)", s.fault_node);
    std::snprintf(b, sizeof b, "\n%u faults; the last: %s (%s) on %s%s, detail 0x%04X, %.1f ms after start",
                  s.faults, to_string(reason), std::string(to_string(s.fault.code)).c_str(),
                  std::string(s.fault.source_name()).c_str(), node, s.fault.detail,
                  static_cast<double>(s.fault.since_start_ns) * 1e-6);
    out += b;
    const auto code = static_cast<std::uint16_t>(s.fault.detail);
    if (reason == FaultReason::emcy || (reason == FaultReason::drive_fault && code != 0))
      out += ": error code " + hex(code) + ", " + std::string(emcy_name(code));
    if (reason == FaultReason::enable_timeout)
      out += ": stuck in " + std::string(cia402::to_string(cia402::decode_state(code)));
    if (reason == FaultReason::mode_mismatch)
      out += ": 0x6061 showed mode " + std::to_string(static_cast<std::int8_t>(s.fault.detail & 0xFF)) +
             ", 0x6060 asked for " + std::to_string(static_cast<std::int8_t>((s.fault.detail >> 8) & 0xFF));
    if (reason == FaultReason::nmt_left)
      out += ": NMT state " + std::string(to_string(static_cast<NmtState>(s.fault.detail)));
  }
  if (s.warnings != 0) {
    std::snprintf(b, sizeof b,
                  "\n%llu warning EMCY (the drive stayed out of fault), the last: %s, %s from node %u",
                  static_cast<unsigned long long>(s.warnings), hex(s.last_warning).c_str(),
                  std::string(emcy_name(s.last_warning)).c_str(), s.last_warning_node);
    out += b;
  }
  if (s.emcy != 0 || s.heartbeat_losses != 0 || s.bad_pdos != 0) {
    std::snprintf(b, sizeof b, "\n%llu EMCY, %llu heartbeat losses, %llu bad PDOs",
                  static_cast<unsigned long long>(s.emcy),
                  static_cast<unsigned long long>(s.heartbeat_losses),
                  static_cast<unsigned long long>(s.bad_pdos));
    out += b;
  }
  // Refused commands and watchdog trips are the device base's: its "device" line says them.
  if (s.sdo_done + s.sdo_failed + s.sdo_refused != 0) {
    std::snprintf(b, sizeof b, "\nruntime SDO: %llu done, %llu failed, %llu refused (queue full)",
                  static_cast<unsigned long long>(s.sdo_done), static_cast<unsigned long long>(s.sdo_failed),
                  static_cast<unsigned long long>(s.sdo_refused));
    out += b;
  }
  return out;
}

}  // namespace

void register_components(deploy::ComponentRegistry& registry) {
  const auto make = [](const std::string& name, const CanopenSpec& s) {
    return std::make_unique<CanopenArm>(name, s.task, s.config);
  };
  registry.add("canopen_drive", "one CiA 402 drive on a CAN bus (CRTK joint commands; csp, csv or cst)",
               parse_drive, make);
  registry.add("canopen_arm", "CiA 402 drives on one CAN bus as a CRTK arm (KDL chain; csp, csv or cst)",
               parse_arm, make);
  registry.add_summary_format<CanopenStatus>(summary_line);
  register_bus_components(registry);
}

}  // namespace saw::canopen
