// WaveVariableLaw: bilateral teleoperation through wave variables — the channel passive by
// construction at any delay (Niemeyer & Slotine 1991).
#pragma once

#include <string_view>
#include <tuple>

#include "saw/teleop/law.hpp"
#include "saw/teleop/law_setting.hpp"
#include "saw/teleop/passivity_port.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

struct WaveVariableSettings {
  double impedance = 2.0;    // N·s/m, b (the master port's must be the same)
  double stiffness = 600.0;  // N/m, the slave's tracking of the wave's velocity, integrated
  double damping = 1.5;      // N·s/m
  double force_limit = 3.0;  // N
};

// The slave's end of the wave transform: the master's port sends u = (b·ẋ_m + F_m)/√(2b); here the
// slave is driven toward x_d, the integral of ẋ_d = (√(2b)·u − F_s)/b, by F_s = K·(x_d − x_s) +
// B·(ẋ_d − ẋ_s) (solved together, saturated), and v = (b·ẋ_d − F_s)/√(2b) goes back, from which
// the master's port makes the force the operator feels. A cycle without a new u is a zero wave.
// Velocities travel, not positions: what the channel loses (a dropped packet) shows as drift.
class WaveVariableLaw {
 public:
  using Settings = WaveVariableSettings;
  static constexpr std::string_view name = "wave_variables";
  static constexpr std::string_view description =
      "bilateral teleoperation through wave variables (passive at any delay; velocities travel, "
      "positions may drift)";
  // The master's port: the wave u it sent (fresh: arrived with this cycle's row; none is a zero
  // wave), its b, which must be the law's (read after the wave: a port restarted with another b
  // shows it with its first wave or before), and the wave v sent back to it.
  static constexpr auto declared_inputs = std::tuple{
      Input<Vec3>{
          LawSide::master, port::wave.name, true,
          "the master's wave port: put a passivity_port with scheme: wave between the master device and "
          "the link"},
      Input<double>{LawSide::master, port::wave_impedance.name, true,
                    "the two ends of a wave channel must share b, or the channel is not passive (0: the port "
                    "runs time-domain passivity); put a passivity_port with scheme: wave and the law's b "
                    "between the master device and the link",
                    "", nullptr, "impedance"}};
  static constexpr auto declared_outputs =
      std::tuple{Output<Vec3>{LawSide::master, port::remote_wave.name, true,
                              "the master's wave port: put a passivity_port with scheme: wave between the "
                              "master device and the link"}};
  static constexpr auto declared_settings = std::tuple{
      // Fixed by the deployment: both ends of the channel must share b (checked against the
      // master's port at start-up and every cycle), and changing it at one end mid-run would
      // break passivity.
      Setting<Settings, double>{"impedance", "N·s/m", 1e-3, 1e3, &Settings::impedance,
                                "wave impedance b, fixed by the deployment: the master port's wave_impedance "
                                "must be the same (checked at start, and every cycle: a port restarted with "
                                "another b is FAULT)",
                                /*command=*/false},
      Setting<Settings, double>{"stiffness", "N/m", 0, max_gain, &Settings::stiffness,
                                "the slave's spring to the wave's integrated velocity"},
      Setting<Settings, double>{"damping", "N·s/m", 0, 100, &Settings::damping, "the slave's damper"},
      Setting<Settings, double>{"force_limit", "N", 0, max_force_limit, &Settings::force_limit,
                                "the slave force's magnitude limit"},
  };

  WaveVariableLaw(const Settings& s, const LawContext& ctx) : s_(s), dt_(ctx.period) {}
  Settings& settings() noexcept { return s_; }
  void reset(const LawInputs& in) noexcept;
  LawCommand step(const LawInputs& in) noexcept;

 private:
  Settings s_;
  double dt_;
  Eigen::Vector3d desired_ = Eigen::Vector3d::Zero();  // x_d
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();   // for the tracking figure: p_m + o = p_s
};

}  // namespace saw::teleop
