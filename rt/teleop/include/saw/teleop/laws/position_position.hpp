// PositionPositionLaw: the slave tracks the master's position (scaled); the master feels nothing.
#pragma once

#include <string_view>
#include <tuple>

#include "saw/teleop/law.hpp"
#include "saw/teleop/law_setting.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

// Unilateral: f_s = −k·e_s − b·v_s saturated to lim, e_s = p_s + o − scale·p_m; f_m = 0. For a
// slave that follows a pose (a PSM), the goal scale·p_m − o instead of the force.
// The offset o cancels e_s while the task holds and on engaging (no force step), and is
// re-expressed when the scale changes (e_s kept).
class PositionPositionLaw {
 public:
  struct Settings {
    double scale = 1.0;
    double stiffness = 100.0;  // N/m
    double damping = 0.0;      // N·s/m
    double force_limit = 3.0;  // N
  };
  static constexpr std::string_view name = "position_position";
  static constexpr bool gives_slave_goal = true;
  static constexpr std::string_view description =
      "the slave tracks the scaled master position (a spring and damper); no force feedback";
  static constexpr auto declared_settings = std::tuple{
      Setting<Settings, double>{"scale", "", min_scale, max_scale, &Settings::scale,
                                "slave displacement per master displacement"},
      Setting<Settings, double>{"stiffness", "N/m", 0, max_gain, &Settings::stiffness, "the slave's spring"},
      Setting<Settings, double>{"damping", "N·s/m", 0, 100, &Settings::damping, "the slave's damper"},
      Setting<Settings, double>{"force_limit", "N", 0, max_force_limit, &Settings::force_limit,
                                "the slave force's magnitude limit"},
  };

  PositionPositionLaw(const Settings& s, const LawContext&) : s_(s) {}
  Settings& settings() noexcept { return s_; }

  void reset(const LawInputs& in) noexcept {
    offset_ = s_.scale * in.master.position - in.slave.position;
    rescaled_from_ = 0;
  }
  void on_set(std::string_view setting, const Settings& before) noexcept {
    if (setting == "scale" && rescaled_from_ == 0) rescaled_from_ = before.scale;
  }
  LawCommand step(const LawInputs& in) noexcept {
    if (rescaled_from_ != 0) {  // keep e_s: o' − scale'·p_m = o − scale·p_m
      offset_ += (s_.scale - rescaled_from_) * in.master.position;
      rescaled_from_ = 0;
    }
    LawCommand out;
    out.slave_error = in.slave.position + offset_ - s_.scale * in.master.position;
    out.master_error = -out.slave_error / s_.scale;
    const Eigen::Vector3d f = -s_.stiffness * out.slave_error - s_.damping * in.slave.velocity;
    out.slave_force = saturate(f, s_.force_limit);
    out.limiting = f.norm() > s_.force_limit;
    out.slave_offset = offset_;
    out.slave_goal = s_.scale * in.master.position - offset_;
    out.finite =
        out.slave_error.allFinite() && f.allFinite() && std::isfinite(f.norm()) && out.slave_goal.allFinite();
    if (!out.finite) out.bad_side = in.master.position.allFinite() ? FaultSide::slave : FaultSide::master;
    return out;
  }

 private:
  Settings s_;
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  double rescaled_from_ = 0;  // the scale before a change not yet applied to the offset; 0: none
};

}  // namespace saw::teleop
