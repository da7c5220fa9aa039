// SurgicalLaw: a surgical instrument follows the master in SE(3) — translation scaled and
// incremental, orientation absolute in the camera frame once aligned, the jaw from the gripper.
#pragma once

#include <Eigen/Geometry>
#include <limits>
#include <string_view>
#include <tuple>

#include "saw/teleop/law.hpp"
#include "saw/teleop/law_setting.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

// The reference is the dVRK's PSM teleoperation (its documentation and mtsTeleOperationPSM's
// behaviour; written here from those, not copied). With C the camera's rotation (the frame the
// operator sees the instrument in: an endoscope's measured_cp on the task's "camera" interface,
// else camera_rpy; taken at each engagement, so a camera moved meanwhile makes no step), at each engagement
// (enable, clutch release, a device idle again) the law takes the master's position p_m0 and the slave's
// p_s0, q_s0, and then:
//   translation  p_goal = p_s0 + scale · C · (p_m − p_m0)       (incremental: no step)
//   orientation  q_goal = C · q_m · q_off, q_off = (C · q_m0)⁻¹ · q_s0  (absolute but for q_off,
//                 which is no more than align_tolerance: no step either)
// It engages only while the master's orientation, seen through C, is within align_tolerance of
// the slave's: until then the slave is held where it was and `misalignment` says how far off the
// master is. A master whose `arm` interface takes move_cp is sent there once at each engagement
// found misaligned — at its position, turned to C⁻¹ · q_s0 — as the dVRK's teleoperation does
// (align_master); no wrench goes to the master until it is busy with the move (a servo command
// would pre-empt it), the task holds while it is, and the law engages again once it is idle;
// else, or if it is stopped on the way, the operator turns the handle. A clutch
// decouples translation; on release the law engages again, orientation checked again. The jaw
// goal is jaw_scale · gripper + jaw_offset within [jaw_min, jaw_max], reached from the slave's
// jaw at no more than jaw_rate (no step at engagement). With `orientation: false` (a 3-DOF master:
// the Falcon) the slave's orientation is held as it was at engagement. The goal sent moves toward
// that pose no faster than max_linear_speed and max_angular_speed: a master stream that arrives in
// bursts (a network, a busy publisher) gives a goal the slave's own step checks take — set them a
// little under the slave device's — instead of steps it refuses.
class SurgicalLaw {
 public:
  struct Settings {
    double scale = 0.2;
    bool orientation = true;
    double align_tolerance = 10.0;  // deg
    bool align_master = true;       // a master that takes move_cp is moved to the alignment
    Vec3 camera_rpy{0, 0, 0};       // deg: roll, pitch, yaw of the camera frame in the slave's base
    double jaw_scale = 1.0, jaw_offset = 0.0;
    double jaw_min = -0.35, jaw_max = 1.4;  // rad
    double jaw_rate = 2.0;                  // rad/s
    double max_linear_speed = 0.18;         // m/s: the goal's fastest move (under dvrk_arm's 0.2)
    double max_angular_speed = 2.7;         // rad/s: its fastest turn (under dvrk_arm's 3)
  };
  static constexpr std::string_view name = "surgical";
  static constexpr bool gives_slave_goal = true;
  static constexpr bool gives_no_force = true;  // a slave that follows a pose only (servo_cp)
  static constexpr std::string_view description =
      "an instrument follows the master in SE(3): translation scaled from engagement, orientation in "
      "the camera frame once aligned, the jaw from the gripper (no force feedback)";
  static constexpr auto declared_settings = std::tuple{
      Setting<Settings, double>{"scale", "", min_scale, max_scale, &Settings::scale,
                                "instrument translation per master translation"},
      Setting<Settings, bool>{"orientation", "", 0, 0, &Settings::orientation,
                              "follow the master's orientation (false: a 3-DOF master; held)", false},
      Setting<Settings, double>{"align_tolerance", "deg", 0.5, 90, &Settings::align_tolerance,
                                "engage only with the master this close to the instrument's orientation"},
      Setting<Settings, bool>{"align_master", "", 0, 0, &Settings::align_master,
                              "move a misaligned master that takes move_cp to the instrument's orientation "
                              "at each engagement (false: the operator turns it)",
                              false},
      Setting<Settings, Vec3>{"camera_rpy", "deg", -180, 180, &Settings::camera_rpy,
                              "the camera frame's roll, pitch, yaw in the slave's base frame", false},
      Setting<Settings, double>{"jaw_scale", "", -10, 10, &Settings::jaw_scale,
                                "jaw angle per gripper angle"},
      Setting<Settings, double>{"jaw_offset", "rad", -3.2, 3.2, &Settings::jaw_offset,
                                "jaw angle at gripper 0"},
      Setting<Settings, double>{"jaw_min", "rad", -3.2, 3.2, &Settings::jaw_min,
                                "the jaw goal's lower limit"},
      Setting<Settings, double>{"jaw_max", "rad", -3.2, 3.2, &Settings::jaw_max,
                                "the jaw goal's upper limit"},
      Setting<Settings, double>{"jaw_rate", "rad/s", 0.01, 20, &Settings::jaw_rate,
                                "the jaw goal's fastest change"},
      Setting<Settings, double>{"max_linear_speed", "m/s", 1e-3, 2, &Settings::max_linear_speed,
                                "the goal's fastest move (under the slave's max_linear_speed)"},
      Setting<Settings, double>{"max_angular_speed", "rad/s", 1e-3, 20, &Settings::max_angular_speed,
                                "the goal's fastest turn (under the slave's max_angular_speed)"},
  };

  // The endoscope: its measured_cp (orientation in the frame of the slave's poses) is the camera
  // frame when the deployment connects a device to the task's "camera" interface; else camera_rpy.
  static constexpr auto declared_inputs = std::tuple{
      Input<Pose>{LawSide::other, "measured_cp", false,
                  "the endoscope's pose, in the frame of the slave's: the camera frame", "camera"}};

  // A master that can be moved: sent the aligned pose once at each engagement found misaligned.
  static constexpr auto declared_outputs = std::tuple{Output<Pose>{
      LawSide::master, "move_cp", false,
      "the master moved to the instrument's orientation (align_master): a master that takes move_cp"}};

  SurgicalLaw(const Settings& s, const LawContext& c);
  Settings& settings() noexcept { return s_; }

  // Engaging (and, by default, holding): the slave is held where it is; engaged once aligned.
  void reset(const LawInputs& in) noexcept;
  LawCommand step(const LawInputs& in) noexcept;

  // Shown as the task's state.
  double misalignment_ = 0;       // deg: the master's orientation (through C) from the slave's
  double aligned_ = 0;            // 1 while aligned (engaged, or to engage), 0 while misaligned
  double orientation_error_ = 0;  // deg: the slave's orientation from its goal
  static constexpr auto declared_readouts = std::tuple{
      Readout<SurgicalLaw, double>{"misalignment", "deg", &SurgicalLaw::misalignment_,
                                   "how far the master's orientation is from the instrument's"},
      Readout<SurgicalLaw, double>{
          "aligned", "", &SurgicalLaw::aligned_,
          "1: aligned (engaged unless held); 0: holding until the master is aligned"},
      Readout<SurgicalLaw, double>{"orientation_error", "deg", &SurgicalLaw::orientation_error_,
                                   "the instrument's orientation from its goal"},
  };

 private:
  // C: the endoscope's orientation when one is connected and has a pose, else camera_rpy.
  Eigen::Quaterniond camera(const LawInputs& in) const noexcept;
  // The master's orientation seen through c; sets misalignment_ and aligned_.
  Eigen::Quaterniond observe(const LawInputs& in, const Eigen::Quaterniond& c) noexcept;
  // Takes the engagement's poses if the master is aligned; true if it is.
  bool engage(const LawInputs& in, const Eigen::Quaterniond& c) noexcept;
  // A misaligned master that takes move_cp: the pose that aligns it (its position, turned).
  void align_master(const LawInputs& in, const Eigen::Quaterniond& c) noexcept;
  double jaw_goal(const LawInputs& in) noexcept;
  // The goal sent: toward (p, q) by no more than the speed limits allow in one period.
  void approach(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) noexcept;

  Settings s_;
  double period_ = 0.001;
  bool engaged_ = false;
  bool align_pending_ = false;  // the first step since a reset: a misaligned master is moved
  bool moving_master_ = false;  // a move sent, the master not yet busy with it: no wrench to it
  Eigen::Quaterniond c_ = Eigen::Quaterniond::Identity();  // C, taken at each engagement
  Eigen::Vector3d p_m0_ = Eigen::Vector3d::Zero(), p_s0_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_s0_ = Eigen::Quaterniond::Identity(), q_off_ = Eigen::Quaterniond::Identity();
  double jaw_ = std::numeric_limits<double>::quiet_NaN();  // the last jaw goal sent
  Eigen::Vector3d p_goal_ = Eigen::Vector3d::Zero();       // the last goal sent
  Eigen::Quaterniond q_goal_ = Eigen::Quaterniond::Identity();
};

}  // namespace saw::teleop
