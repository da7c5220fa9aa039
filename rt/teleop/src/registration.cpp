// The teleop package's types for deployments: each parameter read, range-checked and located.
#include "saw/teleop/registration.hpp"

#include "saw/teleop/collaborative_control_force.hpp"
#include "saw/teleop/delay_task.hpp"

namespace saw::teleop {
namespace {

using namespace std::chrono_literals;
using deploy::ComponentContext;
using deploy::Params;

struct TeleopSpec {
  TaskConfig task;
  TeleopConfig config;
};

TeleopSpec parse_teleop(const ComponentContext& ctx, Params& p) {
  TeleopConfig c;
  c.scale.scale = p.get_in_range("scale", min_scale, max_scale, 1.0);
  c.scale.mirror = p.get_or<Vec3>("mirror", {1, 1, 1});
  if (!c.scale.valid()) p.fail_at("mirror", "each entry must be 1 or -1");
  Params g = p.child("gains");
  c.gains.master = g.get_in_range("master", 0, max_gain, c.gains.master);
  c.gains.slave = g.get_in_range("slave", 0, max_gain, c.gains.slave);
  Params l = p.child("force_limits");
  c.limits.master = l.get_in_range("master", 0, max_force_limit, c.limits.master);
  c.limits.slave = l.get_in_range("slave", 0, max_force_limit, c.limits.slave);
  c.ratchet = p.get_or<bool>("ratchet", true);
  Params o = p.child("offset_limits");
  c.offset_limits.velocity = o.get_in_range("velocity", 1e-6, 10, c.offset_limits.velocity);
  c.offset_limits.acceleration = o.get_in_range("acceleration", 1e-6, 1e3, c.offset_limits.acceleration);
  c.offset_limits.jerk = o.get_in_range("jerk", 1e-6, 1e5, c.offset_limits.jerk);
  Params pr = p.child("prediction");
  c.prediction.enabled = pr.get_or<bool>("enabled", false);
  c.prediction.master_horizon = deploy::seconds_in_range(pr, "master", 0ns, 0, max_horizon);
  c.prediction.slave_horizon = deploy::seconds_in_range(pr, "slave", 0ns, 0, max_horizon);
  c.stale_timeout = deploy::seconds_in_range(p, "stale_timeout", 10ms, 1e-6, 10);
  c.startup_timeout = deploy::seconds_in_range(p, "startup_timeout", 0ns, 0, 600);
  c.device_timeout = deploy::seconds_in_range(p, "device_timeout", 5s, 0.001, 600);
  c.start_enabled = p.get_or<bool>("start_enabled", true);
  c.align = p.get_or<bool>("align", false);
  c.slave_offset = p.get_or<Vec3>("slave_offset", {0, 0, 0});
  return {deploy::periodic_task(ctx, p, "teleop"), c};
}

struct DelaySpec {
  TaskConfig task;
  DelayConfig config;
};

TimeNs duration_in(const Params& p, const std::string& key, std::chrono::nanoseconds fallback) {
  const auto d = p.get_or<std::chrono::nanoseconds>(key, fallback);
  if (d > 10s || d < 0ns) p.fail_at(key, "from 0 to 10 s");
  return d.count();
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

}  // namespace

void register_components(deploy::ComponentRegistry& registry) {
  registry.add("teleop", "collaborative force teleoperation between a master and a slave", parse_teleop,
               [](const std::string& name, const TeleopSpec& s) {
                 return std::make_unique<CollaborativeControlForce>(name, s.task, s.config);
               });
  registry.add("delay", "a simulated network link to a device: delay, jitter and loss, each direction",
               parse_delay, [](const std::string& name, const DelaySpec& s) {
                 return std::make_unique<DelayTask>(name, s.task, s.config);
               });
  registry.add_summary_format<TeleopSummary>([](const TeleopSummary& s) { return to_string(s); });
}

}  // namespace saw::teleop
