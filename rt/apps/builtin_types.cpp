#include "builtin_types.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/eigen.hpp"
#include "saw/teleop/collaborative_control_force.hpp"
#include "saw/teleop/delay_task.hpp"

extern char** environ;

namespace saw::apps {
namespace {

using namespace std::chrono_literals;
using deploy::FactoryContext;
using deploy::Params;

TaskConfig periodic_task(const FactoryContext& ctx, const char* type) {
  TaskConfig t = ctx.task.value_or(TaskConfig::periodic(1ms, 80));
  if (!t.is_periodic())
    ctx.params.fail(std::string(type) + " '" + ctx.name + "' needs a periodic task (task.period)");
  return t;
}

drivers::HandScript parse_hand(Params h, const std::string& directory) {
  using Kind = drivers::HandScript::Kind;
  drivers::HandScript s;
  s.kind = h.get_enum<Kind>(
      "type", {{"none", Kind::none}, {"line", Kind::line}, {"sinusoid", Kind::sinusoid}, {"csv", Kind::csv}},
      Kind::none);
  s.stiffness = h.get_in_range("stiffness", 0, 5000, s.stiffness);
  s.damping = h.get_in_range("damping", 0, 500, s.damping);
  s.from = to_eigen(h.get_or<Vec3>("from", {0, 0, 0}));
  s.to = to_eigen(h.get_or<Vec3>("to", {0, 0, 0}));
  s.duration = h.get_in_range("duration", 1e-3, 1e6, s.duration);
  s.back_and_forth = h.get_or<bool>("back_and_forth", false);
  s.amplitude = to_eigen(h.get_or<Vec3>("amplitude", {0, 0, 0}));
  s.frequency = h.get_in_range("frequency", 0, 100, s.frequency);
  s.phase = h.get_or<double>("phase", 0);
  if (s.kind == Kind::csv) {
    std::filesystem::path file = h.get<std::string>("file");
    if (file.is_relative() && !directory.empty()) file = std::filesystem::path(directory) / file;
    try {
      s.samples = drivers::HandScript::load_csv(file.string());
    } catch (const std::exception& e) {
      h.fail_at("file", e.what());
    }
  }
  return s;
}

std::unique_ptr<Component> make_sim_device(FactoryContext& ctx) {
  Params& p = ctx.params;
  drivers::SimDeviceConfig c;
  c.model = p.get_enum<drivers::ArmModel>(
      "model", {{"omni", drivers::ArmModel::omni}, {"falcon", drivers::ArmModel::falcon}},
      drivers::ArmModel::omni);
  c.initial_joints = to_eigen(p.get_or<Vec3>("initial_joints", {0, 0, 0}));
  c.max_force = p.get_in_range("max_force", 0, 100, 0);
  c.start_enabled = p.get_or<bool>("start_enabled", true);
  c.hand = parse_hand(p.child("hand"), ctx.directory);
  return std::make_unique<drivers::SimHapticDevice>(ctx.name, periodic_task(ctx, "sim_haptic_device"), c);
}

std::unique_ptr<Component> make_teleop(FactoryContext& ctx) {
  Params& p = ctx.params;
  teleop::TeleopConfig c;
  c.scale.scale = p.get_in_range("scale", 1e-3, 1e3, 1.0);
  c.scale.mirror = p.get_or<Vec3>("mirror", {1, 1, 1});
  if (!c.scale.valid()) p.fail_at("mirror", "each entry must be 1 or -1");
  Params g = p.child("gains");
  c.gains.master = g.get_in_range("master", 0, 1e4, c.gains.master);
  c.gains.slave = g.get_in_range("slave", 0, 1e4, c.gains.slave);
  Params l = p.child("force_limits");
  c.limits.master = l.get_in_range("master", 0, 100, c.limits.master);
  c.limits.slave = l.get_in_range("slave", 0, 100, c.limits.slave);
  c.ratchet = p.get_or<bool>("ratchet", true);
  Params o = p.child("offset_limits");
  c.offset_limits.velocity = o.get_in_range("velocity", 1e-6, 10, c.offset_limits.velocity);
  c.offset_limits.acceleration = o.get_in_range("acceleration", 1e-6, 1e3, c.offset_limits.acceleration);
  c.offset_limits.jerk = o.get_in_range("jerk", 1e-6, 1e5, c.offset_limits.jerk);
  Params pr = p.child("prediction");
  c.prediction.enabled = pr.get_or<bool>("enabled", false);
  c.prediction.master_horizon =
      static_cast<double>(pr.get_or<std::chrono::nanoseconds>("master", 0ns).count()) * 1e-9;
  c.prediction.slave_horizon =
      static_cast<double>(pr.get_or<std::chrono::nanoseconds>("slave", 0ns).count()) * 1e-9;
  c.stale_timeout =
      static_cast<double>(p.get_or<std::chrono::nanoseconds>("stale_timeout", 10ms).count()) * 1e-9;
  c.startup_timeout =
      static_cast<double>(p.get_or<std::chrono::nanoseconds>("startup_timeout", 0ns).count()) * 1e-9;
  c.start_enabled = p.get_or<bool>("start_enabled", true);
  c.align = p.get_or<bool>("align", false);
  c.slave_offset = p.get_or<Vec3>("slave_offset", {0, 0, 0});
  return std::make_unique<teleop::CollaborativeControlForce>(ctx.name, periodic_task(ctx, "teleop"), c);
}

std::unique_ptr<Component> make_delay(FactoryContext& ctx) {
  const auto delay = ctx.params.get<std::chrono::nanoseconds>("delay");
  if (delay > 10s) ctx.params.fail_at("delay", "at most 10 s");
  return std::make_unique<teleop::DelayTask>(ctx.name, periodic_task(ctx, "delay"),
                                             static_cast<double>(delay.count()) * 1e-9);
}

// saw-gateway, from the directory saw-rt runs from (both are built into bin/): an ordinary
// process, so that DDS never runs in the RT process. SIGTERM and a wait when the handle goes.
struct GatewayProcess {
  pid_t pid = -1;
  ~GatewayProcess() {
    if (pid <= 0) return;
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
  }
};

std::shared_ptr<void> launch_gateway(const deploy::GatewaySpec& spec) {
  char self[4096] = {};
  const auto n = readlink("/proc/self/exe", self, sizeof self - 1);
  const std::string dir =
      n > 0 ? std::filesystem::path(std::string(self, static_cast<std::size_t>(n))).parent_path().string()
            : ".";
  const std::string exe = dir + "/saw-gateway";
  if (access(exe.c_str(), X_OK) != 0)
    throw std::runtime_error("gateway: " + exe + " not found (build the nonrt/ targets)");
  std::vector<std::string> args{exe,
                                "--exit-with-parent",
                                "--domain",
                                std::to_string(spec.domain),
                                "--decimation",
                                std::to_string(spec.decimation)};
  for (const auto& a : spec.attach) args.insert(args.end(), {"--attach", a});
  for (const auto& i : spec.interfaces) args.insert(args.end(), {"--interface", i});
  for (const auto& m : spec.mirrors) args.insert(args.end(), {"--mirror", m});
  for (const auto& [component, arm] : spec.imports)
    args.insert(args.end(), {"--import", component + "=" + arm});
  if (!spec.ros_namespace.empty()) args.insert(args.end(), {"--ros-namespace", spec.ros_namespace});
  args.insert(args.end(), {"--wait", "30"});  // our own exports go live when the manager starts
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  auto p = std::make_shared<GatewayProcess>();
  if (const int err = posix_spawn(&p->pid, exe.c_str(), nullptr, nullptr, argv.data(), environ); err != 0)
    throw std::runtime_error("gateway: cannot start " + exe + ": " + std::strerror(err));
  // Mirrors of other hosts' components and imported arms: connect() will look for them in this
  // host's bridge.
  std::vector<std::string> wanted = spec.mirrors;
  for (const auto& im : spec.imports) wanted.push_back(im.first);
  for (const auto& m : wanted) {
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    for (;;) {
      try {
        if (bridge::ShmResolver().resolve(m) != nullptr) break;
      } catch (const std::exception&) {  // there, not live yet
      }
      int status = 0;
      if (waitpid(p->pid, &status, WNOHANG) == p->pid) {
        p->pid = -1;
        throw std::runtime_error("gateway: exited before it could present '" + m + "' (see its output)");
      }
      if (std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("gateway: '" + m +
                                 "' was not presented here within 30 s (a mirror: is its host running?)");
      std::this_thread::sleep_for(50ms);
    }
  }
  return p;
}

}  // namespace

void register_builtin_types(deploy::ComponentRegistry& registry) {
  registry.add("sim_haptic_device", make_sim_device,
               "simulated 3-DOF haptic device (Omni- or Falcon-like), KDL");
  registry.add("teleop", make_teleop, "collaborative force teleoperation between a master and a slave");
  registry.add("delay", make_delay, "re-publishes a device's measured_cp/cv `delay` late");
  // Components of other processes on this host, through the shared-memory bridge.
  registry.add_resolver([] { return std::make_unique<bridge::ShmResolver>(); });
  registry.set_exporter([](Component& c, const std::string& provided) -> std::shared_ptr<void> {
    return std::make_shared<bridge::Exporter>(c, provided);
  });
  registry.set_gateway_launcher(launch_gateway);
}

}  // namespace saw::apps
