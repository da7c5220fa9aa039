// The teleop package's types for deployments: each parameter read, range-checked and located.
#include "saw/teleop/registration.hpp"

#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/passivity_port.hpp"
#include "saw/teleop/teleoperation.hpp"

namespace saw::teleop {
namespace {

using namespace std::chrono_literals;
using deploy::ComponentContext;
using deploy::Params;

struct TeleopSpec {
  TaskConfig task;
  TeleopConfig config;
  LawSpec law;
};

TeleopSpec parse_teleop(const ComponentContext& ctx, Params& p) {
  // The law's settings sit beside the task's own keys, each read as the law declares it.
  const auto law = p.get_or<std::string>("law", std::string(CollaborativeLaw::name));
  const LawRegistry* laws = ctx.registry != nullptr ? ctx.registry->find_extension<LawRegistry>() : nullptr;
  if (laws == nullptr) throw std::logic_error("teleop: parsed without the registry that registered it");
  const LawRegistry::Entry* entry = laws->find(law);
  if (entry == nullptr) p.fail_at("law", "'" + law + "' is not one of: " + laws->names());
  TeleopSpec spec{{}, {}, entry->parse(p)};
  TeleopConfig& c = spec.config;
  c.stale_timeout = deploy::seconds_in_range(p, "stale_timeout", 10ms, 1e-6, 10);
  c.startup_timeout = deploy::seconds_in_range(p, "startup_timeout", 0ns, 0, 600);
  c.device_timeout = deploy::seconds_in_range(p, "device_timeout", 5s, 0.001, 600);
  c.start_enabled = p.get_or<bool>("start_enabled", true);
  c.slave_servo_cp = p.get_enum<bool>("slave_command", {{"servo_cf", false}, {"servo_cp", true}}, false);
  c.needs_operator = p.get_or<bool>("needs_operator", false);
  if (c.slave_servo_cp && !spec.law.make(LawContext{})->gives_slave_goal())
    p.fail_at("slave_command", "law '" + law +
                                   "' gives the slave a force only; servo_cp needs a law that gives a "
                                   "position (position_position, surgical)");
  if (!c.slave_servo_cp && spec.law.make(LawContext{})->gives_no_force())
    p.fail_at("law", "law '" + law + "' gives the slave a pose only: it needs slave_command: servo_cp");
  spec.task = deploy::periodic_task(ctx, p, "teleop");
  return spec;
}

struct DelaySpec {
  TaskConfig task;
  DelayConfig config;
};

TimeNs duration_in(const Params& p, const std::string& key, std::chrono::nanoseconds fallback) {
  return p.get_duration_in(key, fallback, 0ns, 10s, "from 0 to 10 s");
}

// One direction of the link: `delay` (required for the measurements), `jitter`, `loss`.
LinkConfig parse_link(const Params& p, std::chrono::nanoseconds default_delay, std::uint64_t seed) {
  LinkConfig l;
  l.delay = p.has("delay") || default_delay < 0ns ? duration_in(p, "delay", 0ns) : default_delay.count();
  l.jitter = duration_in(p, "jitter", 0ns);
  l.loss = p.get_in_range("loss", 0, 0.5, 0);
  l.seed = seed;
  return l;
}

DelaySpec parse_delay(const ComponentContext& ctx, Params& p) {
  if (!p.has("delay")) (void)p.get<std::chrono::nanoseconds>("delay");  // names the missing key
  const auto seed = static_cast<std::uint64_t>(p.get_or<std::int64_t>("seed", 1));
  DelayConfig c;
  c.measured = parse_link(p, -1ns, seed);
  // The command direction: its own `commands: {delay, jitter, loss}`, passed straight through
  // when absent (as before links had two directions).
  if (p.has("commands")) c.commands = parse_link(p.child("commands"), 0ns, seed * 0x9e3779b97f4a7c15ULL + 1);
  c.command_hold = duration_in(p, "command_hold", 0ns);
  return {deploy::periodic_task(ctx, p, "delay"), c};
}

struct PortSpec {
  TaskConfig task;
  PortConfig config;
};

PortSpec parse_port(const ComponentContext& ctx, Params& p) {
  PortConfig c;
  c.scheme = p.get_enum<PortScheme>(
      "scheme", {{"passivity", PortScheme::passivity}, {"wave", PortScheme::wave}}, PortScheme::passivity);
  c.passivity = p.get_or<bool>("passivity", true);
  c.wave_impedance = p.get_in_range("wave_impedance", 1e-3, 1e3, c.wave_impedance);
  c.force_limit = p.get_in_range("force_limit", 0, 100, c.force_limit);
  if (p.has("max_damping")) c.max_damping = p.get_in_range("max_damping", 0, 1e6, 0);
  c.command_hold = duration_in(p, "command_hold", 0ns);
  return {deploy::periodic_task(ctx, p, "passivity_port"), c};
}

}  // namespace

void register_components(deploy::ComponentRegistry& registry) {
  add_builtin_laws(laws(registry));
  registry.add("teleop",
               "teleoperation between a master and a slave under a control law (`law:` " +
                   laws(registry).names() + "; default collaborative)",
               parse_teleop, [](const std::string& name, const TeleopSpec& s) {
                 return std::make_unique<Teleoperation>(name, s.task, s.config, s.law);
               });
  registry.add("delay", "a simulated network link to a device: delay, jitter and loss, each direction",
               parse_delay, [](const std::string& name, const DelaySpec& s) {
                 return std::make_unique<DelayTask>(name, s.task, s.config);
               });
  registry.add("passivity_port",
               "the master's end of a passive bilateral teleoperation: energy observed and the passivity "
               "controller applied beside the device",
               parse_port, [](const std::string& name, const PortSpec& s) {
                 return std::make_unique<PassivityPort>(name, s.task, s.config);
               });
  registry.add_summary_format<TeleopSummary>([](const TeleopSummary& s) { return to_string(s); });
}

}  // namespace saw::teleop
