// force_sensor_feedback: a control law a lab writes itself that needs an input the teleoperation
// task does not read for any other law — the slave's measured wrench (a force sensor at its tip,
// CRTK measured_cf) — and gets it by declaring it. Position–force (two-channel) teleoperation:
// the slave follows the master through a spring and damper, the operator feels the force the
// sensor measures, not the coupling's.
//
// The whole law is this file: the struct, and one registration line at the end. No edit of the
// task: `declared_inputs` asks it to require `measured_cf` on the slave's interface (a deployment
// whose slave has none fails to start, naming it), to read it every cycle, to hand over only
// valid values, and to FAULT if it goes without one for the task's stale_timeout.
#include <cmath>
#include <saw/crtk_arm.hpp>
#include <saw/deploy/plugin.hpp>
#include <saw/eigen.hpp>
#include <saw/teleop/law_registry.hpp>
#include <saw/teleop/teleop_law.hpp>

namespace lab {

using saw::teleop::LawCommand;
using saw::teleop::LawContext;
using saw::teleop::LawInputs;
using saw::teleop::Setting;

// e = p_s + o − p_m; f_s = −k·e − b·(v_s − v_m), saturated; f_m = feedback · F_sensor (the
// environment's push on the slave's tip, reflected to the operator's hand).
struct ForceSensorFeedbackLaw {
  struct Settings {
    double stiffness = 300;  // N/m, the slave's position servo
    double damping = 2;      // N·s/m
    double feedback = 1.0;   // share of the sensed force the operator feels
    double force_limit = 3;  // N, each side
  };
  static constexpr std::string_view name = "force_sensor_feedback";
  static constexpr std::string_view description =
      "example lab law: the slave follows in position, the master feels the slave's force sensor";
  static constexpr auto declared_settings = std::tuple{
      Setting<Settings, double>{"stiffness", "N/m", 0, 2000, &Settings::stiffness,
                                "the slave's servo spring"},
      Setting<Settings, double>{"damping", "N·s/m", 0, 50, &Settings::damping, "the slave's servo damper"},
      Setting<Settings, double>{"feedback", "", 0, 2, &Settings::feedback,
                                "share of the sensed force fed back"},
      Setting<Settings, double>{"force_limit", "N", 0, 10, &Settings::force_limit, "|f| limit, each side"},
  };
  // The input no built-in law reads: the slave's measured wrench, by CRTK name and type.
  static constexpr auto declared_inputs = std::tuple{saw::teleop::Input<saw::Wrench>{
      saw::teleop::LawSide::slave, saw::crtk::arm::measured_cf.name, true, "the slave's tip force sensor"}};

  ForceSensorFeedbackLaw(const Settings& s, const LawContext&) : s_(s) {}
  Settings& settings() noexcept { return s_; }

  // Runs in the RT thread, like step(): no allocation, lock, I/O or exception.
  void reset(const LawInputs& in) noexcept { offset_ = in.master.position - in.slave.position; }
  LawCommand step(const LawInputs& in) noexcept {
    LawCommand out;
    out.slave_error = in.slave.position + offset_ - in.master.position;
    out.master_error = -out.slave_error;
    const Eigen::Vector3d f =
        -s_.stiffness * out.slave_error - s_.damping * (in.slave.velocity - in.master.velocity);
    out.slave_force = saw::teleop::saturate(f, s_.force_limit);
    // Declared input 0; the task hands it over checked (finite), the last valid one if a read failed.
    Eigen::Vector3d sensed = Eigen::Vector3d::Zero();
    if (const saw::Wrench* w = in.declared.get<saw::Wrench>(0)) sensed = saw::to_eigen(w->force);
    sensed_ = sensed.norm();
    const Eigen::Vector3d fm = s_.feedback * sensed;
    out.master_force = saw::teleop::saturate(fm, s_.force_limit);
    out.limiting = f.norm() > s_.force_limit || fm.norm() > s_.force_limit;
    out.slave_offset = offset_;
    out.finite = f.allFinite() && fm.allFinite() && std::isfinite(f.norm());
    return out;
  }

 private:
  Settings s_;
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  double sensed_ = 0;  // N

 public:
  static constexpr auto declared_readouts = std::tuple{saw::teleop::Readout<ForceSensorFeedbackLaw, double>{
      "sensed_force", "N", &ForceSensorFeedbackLaw::sensed_, "|the slave's measured force|, this cycle"}};
};

void register_law(saw::deploy::ComponentRegistry& r) { saw::teleop::laws(r).add<ForceSensorFeedbackLaw>(); }

}  // namespace lab

SAW_PLUGIN(lab::register_law)
