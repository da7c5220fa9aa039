// The sim package's types for deployments: each parameter read, range-checked and located.
#include "saw/drivers/sim_registration.hpp"

#include <cmath>
#include <filesystem>

#include "saw/deploy/device_settings.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/drivers/sim_instrument.hpp"
#include "saw/eigen.hpp"

namespace saw::drivers::sim {
namespace {

using namespace std::chrono_literals;
using deploy::ComponentContext;
using deploy::Params;

HandScript parse_hand(Params h, const std::string& directory) {
  using Kind = HandScript::Kind;
  HandScript s;
  s.kind = h.get_enum<Kind>("type",
                            {{"none", Kind::none},
                             {"line", Kind::line},
                             {"sinusoid", Kind::sinusoid},
                             {"csv", Kind::csv},
                             {"reach", Kind::reach}},
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
  if (s.kind == Kind::reach) {
    for (const Vec3& p : h.get<std::vector<Vec3>>("targets")) {
      if (std::abs(p[0]) > 0.5 || std::abs(p[1]) > 0.5 || std::abs(p[2]) > 0.5)
        h.fail_at("targets", "a target is more than 0.5 m from the hand's origin");
      s.targets.push_back(to_eigen(p));
    }
    if (s.targets.empty()) h.fail_at("targets", "needs at least one target");
  }
  s.reach_time = h.get_in_range("reach_time", 1e-2, 60, s.reach_time);
  s.dwell = h.get_in_range("dwell", 0, 60, s.dwell);
  // A stylus's hand (the device's `stylus: true`): its turn (deg about an axis of the base's
  // frame) and grip (rad), sinusoids at the script's frequency and phase.
  if (h.has("turn")) {
    const Params turn = h.child("turn");
    s.turn_axis = to_eigen(turn.get<Vec3>("axis"));
    if (!(s.turn_axis.norm() > 1e-9)) turn.fail_at("axis", "must not be zero");
    s.turn_amplitude = turn.get_in_range("amplitude", 0, 180, 0) * M_PI / 180;
  }
  if (h.has("grip")) {
    const Params grip = h.child("grip");
    s.grip_mean = grip.get_in_range("mean", -1.6, 1.6, 0);
    s.grip_amplitude = grip.get_in_range("amplitude", 0, 1.6, 0);
  }
  // The operator's clutch: pressed and released at these times (s), alternately.
  if (h.has("clutch")) {
    const auto times = h.get<std::vector<double>>("clutch");
    if (times.size() % 2 != 0)
      h.fail_at("clutch", "pairs of times: pressed at the first, released at the second");
    for (std::size_t i = 0; i < times.size(); i += 2) {
      if (!(times[i] >= 0 && times[i] < times[i + 1]) || (i > 0 && !(times[i] > times[i - 1])))
        h.fail_at("clutch", "times increasing, each release after its press");
      s.clutch_windows.emplace_back(times[i], times[i + 1]);
    }
  }
  const Params tremor = h.child("tremor");
  s.tremor_amplitude = tremor.get_in_range("amplitude", 0, 0.002, 0.0);
  s.tremor_frequency = tremor.get_in_range("frequency", 0.1, 30, s.tremor_frequency);
  if (s.kind == Kind::csv) {
    std::filesystem::path file = h.get<std::string>("file");
    if (file.is_relative() && !directory.empty()) file = std::filesystem::path(directory) / file;
    try {
      s.samples = HandScript::load_csv(file.string());
    } catch (const std::exception& e) {
      h.fail_at("file", e.what());
    }
  }
  return s;
}

struct SimDeviceSpec {
  TaskConfig task;
  SimDeviceConfig config;
};

SimDeviceSpec parse_sim_device(const ComponentContext& ctx, Params& p) {
  SimDeviceConfig c;
  c.model =
      p.get_enum<ArmModel>("model", {{"omni", ArmModel::omni}, {"falcon", ArmModel::falcon}}, ArmModel::omni);
  c.initial_joints = to_eigen(p.get_or<Vec3>("initial_joints", {0, 0, 0}));
  c.hand = parse_hand(p.child("hand"), ctx.directory);
  c.stylus = p.get_or<bool>("stylus", false);
  if (c.stylus && c.model != ArmModel::omni) p.fail_at("stylus", "an Omni's (model: omni)");
  if (p.has("gimbal")) {
    const Params g = p.child("gimbal");
    c.gimbal_min = to_eigen(g.get<Vec3>("min"));
    c.gimbal_max = to_eigen(g.get<Vec3>("max"));
    if ((c.gimbal_min.array() >= c.gimbal_max.array()).any())
      g.fail_at("max", "must be above min on every axis");
  }
  if (p.has("wall")) {
    const Params w = p.child("wall");
    c.wall.enabled = true;
    c.wall.point = to_eigen(w.get_or<Vec3>("point", {0, 0, 0}));
    c.wall.normal = to_eigen(w.get<Vec3>("normal"));
    if (!(c.wall.normal.norm() > 1e-9)) w.fail_at("normal", "must not be zero");
    c.wall.stiffness = w.get_in_range("stiffness", 0, 1e5, c.wall.stiffness);
    c.wall.damping = w.get_in_range("damping", 0, 1e3, c.wall.damping);
  }
  const TaskConfig task = deploy::periodic_task(ctx, p, "sim_haptic_device");
  c.contract = deploy::parse_device_settings(p, task, {.most_force = 100}, c.contract);
  return {task, c};
}

struct SimInstrumentSpec {
  TaskConfig task;
  SimInstrumentConfig config;
};

SimInstrumentSpec parse_sim_instrument(const ComponentContext& ctx, Params& p) {
  SimInstrumentSpec s;
  SimInstrumentConfig& c = s.config;
  s.task = deploy::periodic_task(ctx, p, "sim_instrument");
  c.contract = deploy::parse_device_settings(p, s.task, {.force = false, .poses = true}, c.contract);
  if (p.has("initial_joints")) {
    const auto q = p.get<std::vector<double>>("initial_joints");
    if (q.size() != InstrumentKinematics::dof) p.fail_at("initial_joints", "six values, base to wrist");
    for (int i = 0; i < InstrumentKinematics::dof; ++i) {
      c.initial_joints[i] = q[static_cast<std::size_t>(i)];
      if (!(q[static_cast<std::size_t>(i)] >= c.joint_min[i] &&
            q[static_cast<std::size_t>(i)] <= c.joint_max[i]))
        p.fail_at("initial_joints", "each within its joint's stops");
    }
  }
  c.servo_lag = seconds_in_range(p, "servo_lag", std::chrono::microseconds(5000), 0, 0.5);
  c.jaw_min = p.get_in_range("jaw_min", -1, 2, c.jaw_min);
  c.jaw_max = p.get_in_range("jaw_max", -1, 2, c.jaw_max);
  if (!(c.jaw_min < c.jaw_max)) p.fail_at("jaw_max", "must be above jaw_min");
  c.jaw_rate = p.get_in_range("jaw_rate", 0.01, 100, c.jaw_rate);
  c.initial_jaw = p.get_in_range("initial_jaw", c.jaw_min, c.jaw_max, c.initial_jaw);
  return s;
}

}  // namespace

void register_components(deploy::ComponentRegistry& registry) {
  registry.add("sim_haptic_device",
               "simulated 3-DOF haptic device (Omni-like arm, KDL; or the Falcon's delta)", parse_sim_device,
               [](const std::string& name, const SimDeviceSpec& s) {
                 return std::make_unique<SimHapticDevice>(name, s.task, s.config);
               });
  registry.add(
      "sim_instrument",
      "simulated PSM-like instrument arm (remote centre, wrist, jaw; KDL) taking servo_cp and jaw_servo_jp",
      parse_sim_instrument, [](const std::string& name, const SimInstrumentSpec& s) {
        return std::make_unique<SimInstrument>(name, s.task, s.config);
      });
}

}  // namespace saw::drivers::sim
