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
  double delay = 0;  // s
};

DelaySpec parse_delay(const ComponentContext& ctx, Params& p) {
  const auto delay = p.get<std::chrono::nanoseconds>("delay");
  if (delay > 10s || delay < 0ns) p.fail_at("delay", "from 0 to 10 s");
  return {deploy::periodic_task(ctx, p, "delay"), static_cast<double>(delay.count()) * 1e-9};
}

}  // namespace

void register_components(deploy::ComponentRegistry& registry) {
  registry.add("teleop", "collaborative force teleoperation between a master and a slave", parse_teleop,
               [](const std::string& name, const TeleopSpec& s) {
                 return std::make_unique<CollaborativeControlForce>(name, s.task, s.config);
               });
  registry.add("delay", "re-publishes a device's measured_cp/cv `delay` late", parse_delay,
               [](const std::string& name, const DelaySpec& s) {
                 return std::make_unique<DelayTask>(name, s.task, s.delay);
               });
  registry.add_summary_format<TeleopSummary>([](const TeleopSummary& s) { return to_string(s); });
}

}  // namespace saw::teleop
