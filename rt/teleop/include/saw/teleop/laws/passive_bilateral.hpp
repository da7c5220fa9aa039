// PassiveBilateralLaw: the paper's bilateral coupling made passive at any delay by time-domain
// passivity on both ports.
#pragma once

#include <string_view>
#include <tuple>

#include "saw/teleop/law.hpp"
#include "saw/teleop/law_setting.hpp"
#include "saw/teleop/passivity.hpp"
#include "saw/teleop/passivity_port.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

struct PassiveBilateralSettings {
  double scale = 1.0;
  Gains gains{600, 600};
  double damping = 1.5;  // N·s/m, on the velocity difference (both sides)
  ForceLimits limits{3, 3};
  bool passivity = true;
};

// Each side pulled toward the other (the paper's eqs. 3–6 without the ratchet): with
// e_s = p_s + o − scale·p_m, f_s = −k_s·e_s − b·(v_s − scale·v_m) and
// f_m = (k_m·e_s + b·(v_s − scale·v_m)) / scale, each saturated to its limit. The task runs beside
// the slave, so the slave's port is observed and controlled here; the master's is a
// PassivityPort beside the master. Each port gives its device no more energy than has entered at
// the other port, received over the link (Hannaford & Ryu 2002; Ryu, Kwon & Hannaford 2004):
// stable at any delay, loss and jitter, transparent when the channel is.
class PassiveBilateralLaw {
 public:
  using Settings = PassiveBilateralSettings;
  static constexpr std::string_view name = "passive_bilateral";
  static constexpr std::string_view description =
      "bilateral spring-damper coupling (force feedback) kept passive at any delay by time-domain "
      "passivity on both ports";
  static bool valid_energy(const double& e) noexcept { return e >= 0; }
  // The master's passivity port: the energy that entered there, as it arrived (late by the
  // link's delay; ≥ 0, only growing), and the slave port's energy sent back to it.
  static constexpr auto declared_inputs = std::tuple{Input<double>{
      LawSide::master, port::energy.name, true,
      "the master's passivity port: put a passivity_port component between the master device and the link",
      "", &valid_energy}};
  static constexpr auto declared_outputs = std::tuple{Output<double>{
      LawSide::master, port::remote_energy.name, true,
      "the master's passivity port: put a passivity_port component between the master device and the link"}};
  static constexpr auto declared_settings = std::tuple{
      Setting<Settings, double>{"scale", "", min_scale, max_scale, &Settings::scale,
                                "slave displacement per master displacement"},
      Setting<Settings, Gains>{"gains", "N/m", 0, max_gain, &Settings::gains, "coupling stiffness k_m, k_s"},
      Setting<Settings, double>{"damping", "N·s/m", 0, 100, &Settings::damping,
                                "coupling damping on the velocity difference"},
      Setting<Settings, ForceLimits>{"force_limits", "N", 0, max_force_limit, &Settings::limits,
                                     "force magnitude limits lim_m, lim_s"},
      Setting<Settings, bool>{"passivity", "", 0, 1, &Settings::passivity,
                              "the passivity controller on the slave's port (off: observe only)"},
  };

  PassiveBilateralLaw(const Settings& s, const LawContext& ctx);
  Settings& settings() noexcept { return s_; }
  void reset(const LawInputs& in) noexcept;
  void on_set(std::string_view setting, const Settings& before) noexcept;
  LawCommand step(const LawInputs& in) noexcept;

  // Read-outs (J, N·s/m): the slave port's energy, what its controller took out, and the master
  // port's input energy as received.
  double slave_energy_in_ = 0, slave_energy_out_ = 0, slave_dissipated_ = 0, slave_damping_ = 0;
  double master_energy_in_ = 0;
  static constexpr auto declared_readouts = std::tuple{
      Readout<PassiveBilateralLaw, double>{"slave_port_in", "J", &PassiveBilateralLaw::slave_energy_in_,
                                           "energy that entered the network at the slave"},
      Readout<PassiveBilateralLaw, double>{"slave_port_out", "J", &PassiveBilateralLaw::slave_energy_out_,
                                           "energy the network gave the slave"},
      Readout<PassiveBilateralLaw, double>{"slave_port_dissipated", "J",
                                           &PassiveBilateralLaw::slave_dissipated_,
                                           "energy the slave port's controller took out"},
      Readout<PassiveBilateralLaw, double>{"slave_port_damping", "N·s/m",
                                           &PassiveBilateralLaw::slave_damping_,
                                           "the controller's damping this cycle"},
      Readout<PassiveBilateralLaw, double>{"master_port_in", "J", &PassiveBilateralLaw::master_energy_in_,
                                           "energy that entered at the master, as received"},
  };

 private:
  Settings s_;
  double dt_;
  PassivityController slave_port_;
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  double rescaled_from_ = 0;  // the scale before a change not yet applied to the offset; 0: none
};

}  // namespace saw::teleop
