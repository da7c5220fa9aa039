// The dVRK package's type for deployments: each parameter read, range-checked and located.
#include "saw/drivers/dvrk/registration.hpp"

#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "saw/deploy/device_settings.hpp"
#include "saw/drivers/dvrk/dvrk_arm.hpp"

namespace saw::drivers::dvrk {
namespace {

using namespace std::chrono_literals;
using deploy::Params;

struct DvrkArmSpec {
  TaskConfig task;
  DvrkArmConfig arm;
};

TimeNs duration_in(const Params& p, const std::string& key, TimeNs fallback, TimeNs lo, TimeNs hi,
                   const char* what) {
  using ns = std::chrono::nanoseconds;
  return p.get_duration_in(key, ns(fallback), ns(lo), ns(hi), what);
}

// joints: {names: [...], min: [...], max: [...], max_velocity: [...]}: one entry per joint, as
// the arm's measured_js names them (rad or m; max_velocity, servo_jp's step rate, optional).
std::vector<JointLimits> parse_joints(const Params& p) {
  std::vector<JointLimits> out;
  if (!p.has("joints")) return out;
  const Params j = p.child("joints");
  const auto names = j.get<std::vector<std::string>>("names");
  if (names.empty() || names.size() > JointState::max_joints) j.fail_at("names", "one to eight joints");
  const auto list = [&](const char* key, double fallback) {
    auto v = j.get_or<std::vector<double>>(key, std::vector<double>(names.size(), fallback));
    if (v.size() != names.size())
      j.fail_at(key, "one value per joint (" + std::to_string(names.size()) + ")");
    return v;
  };
  const auto min = list("min", -std::numeric_limits<double>::infinity());
  const auto max = list("max", std::numeric_limits<double>::infinity());
  const auto velocity = list("max_velocity", std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty() || names[i].size() > JointState::max_name)
      j.fail_at("names", "a name of 1 to 31 characters");
    if (!(min[i] < max[i])) j.fail_at("max", "must be above min for " + names[i]);
    if (!(velocity[i] > 0)) j.fail_at("max_velocity", "must be positive for " + names[i]);
    out.push_back(JointLimits{names[i], min[i], max[i], velocity[i]});
  }
  return out;
}

DvrkArmSpec parse_dvrk_arm(const deploy::ComponentContext& ctx, Params& p) {
  DvrkArmSpec s;
  s.task = deploy::periodic_task(ctx, p, "dvrk_arm");
  const TimeNs period = s.task.period.count();
  DvrkArmConfig& c = s.arm;
  c.kind = p.get_enum<ArmKind>("kind", {{"mtm", ArmKind::mtm}, {"psm", ArmKind::psm}, {"ecm", ArmKind::ecm}},
                               ArmKind::mtm);
  if (!p.has("kind")) p.fail_at("kind", "say which arm this is: mtm, psm or ecm");
  const bool psm = follows_poses(c.kind);
  c.safe_command = p.get_enum<SafeCommand>("safe_command",
                                           {{"zero_wrench", SafeCommand::zero_wrench},
                                            {"hold", SafeCommand::hold},
                                            {"servo_cp_measured", SafeCommand::servo_cp_measured}},
                                           psm ? SafeCommand::hold : SafeCommand::zero_wrench);
  if (psm && c.safe_command == SafeCommand::zero_wrench)
    p.fail_at("safe_command", "a PSM's or ECM's is hold or servo_cp_measured (a zero wrench lets it drop)");
  if (!psm && c.safe_command == SafeCommand::servo_cp_measured)
    p.fail_at("safe_command", "an MTM's is zero_wrench or hold");
  c.contract = deploy::parse_device_settings(
      p, s.task, {.force = !psm, .most_force = 20, .homes = true, .poses = psm}, c.contract);
  // The dVRK publishes at 100 Hz by default (its -p 0.01): three samples' worth at least.
  c.stale_timeout =
      duration_in(p, "stale_timeout", c.stale_timeout, 3 * period, std::chrono::nanoseconds(2s).count(),
                  "at least three periods and at most 2 s");
  c.home = p.get_or<bool>("home", false);
  c.joints = parse_joints(p);
  c.servo_jp = p.get_or<bool>("servo_jp", false);
  if (c.servo_jp && c.joints.empty())
    p.fail_at("servo_jp", "needs the arm's joints (joints: {names: [...]})");
  if (c.kind == ArmKind::psm) {
    c.jaw_min = p.get_in_range("jaw_min", -1, 2, c.jaw_min);
    c.jaw_max = p.get_in_range("jaw_max", -1, 2, c.jaw_max);
    if (!(c.jaw_min < c.jaw_max)) p.fail_at("jaw_max", "must be above jaw_min");
  }
  if (psm) {
    c.following_error = p.get_in_range("following_error", 0, 0.5, c.following_error);
    c.following_time =
        duration_in(p, "following_time", c.following_time, period, std::chrono::nanoseconds(10s).count(),
                    "at least one period and at most 10 s");
  }
  return s;
}

std::string summary_line(const DvrkSummary& s) {
  char b[400];
  std::snprintf(b, sizeof b,
                "%llu motion commands, %llu safe commands, %llu held back while the arm was busy, %llu not "
                "taken by the import, %llu poses refused, %llu jaw commands (%llu refused), %llu moves (%llu "
                "refused), %llu joint samples refused; the dVRK arm last %s%s%s",
                static_cast<unsigned long long>(s.commands), static_cast<unsigned long long>(s.safe_commands),
                static_cast<unsigned long long>(s.held_busy), static_cast<unsigned long long>(s.not_sent),
                static_cast<unsigned long long>(s.bad_poses), static_cast<unsigned long long>(s.jaw_commands),
                static_cast<unsigned long long>(s.jaw_refused), static_cast<unsigned long long>(s.moves),
                static_cast<unsigned long long>(s.moves_refused),
                static_cast<unsigned long long>(s.bad_joint_states), to_string(s.arm.state).data(),
                s.arm.is_homed ? ", homed" : "", s.arm.is_busy ? ", busy" : "");
  return b;
}

}  // namespace

void register_components(deploy::ComponentRegistry& registry) {
  registry.add("dvrk_arm",
               "a dVRK arm (MTM: servo_cf; PSM: servo_cp) through the gateway's import of its CRTK topics",
               parse_dvrk_arm, [](const std::string& name, const DvrkArmSpec& s) {
                 return std::make_unique<DvrkArm>(name, s.task, s.arm);
               });
  registry.add_summary_format<DvrkSummary>(summary_line);
}

}  // namespace saw::drivers::dvrk
