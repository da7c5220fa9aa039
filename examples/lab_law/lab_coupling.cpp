// lab_coupling: a control law a lab writes itself — a virtual coupling (spring and damper)
// between master and slave, the master feeling a chosen share of the slave's force — run by
// sawrt's teleoperation task (`type: teleop`, `law: lab_coupling`) from a plug-in.
//
// The whole law is this file: the struct, and one registration line at the end.
#include <cmath>
#include <saw/deploy/plugin.hpp>
#include <saw/teleop/law_registry.hpp>
#include <saw/teleop/teleop_law.hpp>

namespace lab {

using saw::teleop::LawCommand;
using saw::teleop::LawContext;
using saw::teleop::LawInputs;
using saw::teleop::Setting;

// e = p_s + o − p_m; f_s = −k·e − b·(v_s − v_m), saturated to lim; f_m = −feedback·f_s.
// The offset o cancels e on engaging, so that enabling or releasing the clutch makes no force.
struct CouplingLaw {
  struct Settings {
    double stiffness = 200;  // N/m
    double damping = 1;      // N·s/m
    double feedback = 0.5;   // share of the slave's force the operator feels
    double force_limit = 3;  // N
  };
  static constexpr std::string_view name = "lab_coupling";
  static constexpr std::string_view description =
      "example lab law: a spring and damper between master and slave, part of the force fed back";
  // Each setting: its deployment key, its command set_<name>, its bounds, its read-back.
  static constexpr auto declared_settings = std::tuple{
      Setting<Settings, double>{"stiffness", "N/m", 0, 2000, &Settings::stiffness, "the coupling's spring"},
      Setting<Settings, double>{"damping", "N·s/m", 0, 50, &Settings::damping, "the coupling's damper"},
      Setting<Settings, double>{"feedback", "", 0, 1, &Settings::feedback, "share of f_s fed back"},
      Setting<Settings, double>{"force_limit", "N", 0, 10, &Settings::force_limit, "|f_s| limit"},
  };

  CouplingLaw(const Settings& s, const LawContext&) : s_(s) {}
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
    out.master_force = -s_.feedback * out.slave_force;
    out.limiting = f.norm() > s_.force_limit;
    out.slave_offset = offset_;
    out.finite = f.allFinite() && std::isfinite(f.norm());
    // What the coupling has given the devices (a passivity observer would watch this grow).
    if (out.finite)
      energy_ +=
          (out.master_force.dot(in.master.velocity) + out.slave_force.dot(in.slave.velocity)) * in.period;
    return out;
  }

 private:
  Settings s_;
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  double energy_ = 0;  // J

 public:
  // A value the law computes, shown as the task's state and read command `energy`.
  static constexpr auto declared_readouts = std::tuple{saw::teleop::Readout<CouplingLaw, double>{
      "energy", "J", &CouplingLaw::energy_, "work done by the coupling on both devices"}};
};

void register_law(saw::deploy::ComponentRegistry& r) { saw::teleop::laws(r).add<CouplingLaw>(); }

}  // namespace lab

SAW_PLUGIN(lab::register_law)
