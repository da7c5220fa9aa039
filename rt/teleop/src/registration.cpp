// The teleop package's types for deployments: each parameter read, range-checked and located.
#include "saw/teleop/registration.hpp"

#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/laws/collaborative.hpp"
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
  const LawRegistry::Entry* entry = law_registry().find(law);
  if (entry == nullptr) p.fail_at("law", "'" + law + "' is not one of: " + law_registry().names());
  TeleopSpec spec{{}, {}, entry->parse(p)};
  TeleopConfig& c = spec.config;
  c.stale_timeout = deploy::seconds_in_range(p, "stale_timeout", 10ms, 1e-6, 10);
  c.startup_timeout = deploy::seconds_in_range(p, "startup_timeout", 0ns, 0, 600);
  c.device_timeout = deploy::seconds_in_range(p, "device_timeout", 5s, 0.001, 600);
  c.start_enabled = p.get_or<bool>("start_enabled", true);
  spec.task = deploy::periodic_task(ctx, p, "teleop");
  return spec;
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
  registry.add("teleop",
               "teleoperation between a master and a slave under a control law (`law:` " +
                   law_registry().names() + "; default collaborative)",
               parse_teleop, [](const std::string& name, const TeleopSpec& s) {
                 return std::make_unique<Teleoperation>(name, s.task, s.config, s.law);
               });
  registry.add("delay", "re-publishes a device's measured_cp/cv `delay` late", parse_delay,
               [](const std::string& name, const DelaySpec& s) {
                 return std::make_unique<DelayTask>(name, s.task, s.delay);
               });
  registry.add_summary_format<TeleopSummary>([](const TeleopSummary& s) { return to_string(s); });
}

}  // namespace saw::teleop
