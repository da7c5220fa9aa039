// SimHapticDevice: a simulated 3-DOF force-feedback device (an Omni-like arm, a Falcon) as a periodic task.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "saw/device.hpp"
#include "saw/drivers/arm_kinematics.hpp"
#include "saw/drivers/hand_script.hpp"
#include "saw/eigen.hpp"

namespace saw::drivers {

// A stiff virtual wall the tip can push into (a tool in contact with tissue or a fixture): the
// plane through `point` (relative to the initial tip position) with outward unit `normal`; past
// it the wall pushes back along the normal with stiffness·depth + damping·(inward speed), never
// pulling.
struct VirtualWall {
  bool enabled = false;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
  double stiffness = 2000.0;  // N/m
  double damping = 5.0;       // N·s/m
};

struct SimDeviceConfig {
  // The base's settings; max_force 0: the model's (Omni 3.3 N, Falcon 9 N). With no fresh
  // servo_cf for command_timeout (0: 3 periods) the device applies zero force (a dead
  // teleoperation process must not leave it pushing).
  DeviceSettings contract;
  ArmModel model = ArmModel::omni;
  // rad; zero: the model's default (Omni: elbow bent 1.2 rad; Falcon: every arm at 35°).
  Eigen::Vector3d initial_joints = Eigen::Vector3d::Zero();
  Eigen::Vector3d inertia = Eigen::Vector3d::Zero();  // zero: the model's default
  Eigen::Vector3d damping = Eigen::Vector3d::Zero();  // zero: the model's default
  Eigen::Vector3d joint_min = Eigen::Vector3d::Zero(),
                  joint_max = Eigen::Vector3d::Zero();  // equal: defaults
  HandScript hand;
  VirtualWall wall;
  int substeps = 4;  // integration steps per cycle
  // A 6-DOF Omni-like stylus (model omni): on the arm's tip a gimbal of three intersecting axes
  // — about y, then x, then z of the tip's frame — sensed, with no motors (force feedback stays
  // 3-DOF, as on an Omni), and a gripper; the hand turns the stylus and squeezes the gripper
  // (HandScript's turn and grip). measured_cp's orientation is the stylus's (the hand's, within
  // the gimbal's limits), measured_js has the gimbal's joints after the arm's,
  // gripper_measured_js the grip (rad).
  bool stylus = false;
  Eigen::Vector3d gimbal_min{-2.6, -1.4, -2.6}, gimbal_max{2.6, 1.4, 2.6};  // rad
};

// Buttons on the "sim" interface's set_button.
struct ButtonCommand {
  static constexpr std::string_view type_name = "saw::drivers::ButtonCommand";
  static constexpr std::uint32_t layout_version = 1;
  std::uint8_t button = 0;  // 0 clutch, 1 operator_present
  bool pressed = false;
};
// Crosses processes byte for byte (set_button).
static_assert(sizeof(ButtonCommand) == 2 && offsetof(ButtonCommand, pressed) == 1);

// Provided "arm" (CRTK, by the device base: saw/device.hpp): measured_cp, measured_cv,
// measured_js (with the model's joint names), operating_state, fault, command_timeout,
// watchdog_trips (reads); servo_cf, state_command (writes); operating_state, fault, clutch,
// operator_present (events); also servo_force (the force applied this cycle).
// Provided "sim": set_button (write), hand_force, wall_force, rejected_commands, and the work
// done on the arm by its motors, the hand and the wall (reads).
// The work (J, cumulative since start) is the physics' own: each force as applied, dotted with
// the tip's displacement in every substep — not the controller's force and velocity samples, so
// an energy figure built on it checks a passivity controller rather than reading its bound back.
// The base checks every servo_cf (finite, |force| <= max_force) and runs the watchdog; this
// driver is the simulated hardware: the hand, the dynamics and the stops.
class SimHapticDevice : public Device {
 public:
  SimHapticDevice(std::string name, TaskConfig task, SimDeviceConfig config);

  const SimDeviceConfig& device_config() const noexcept { return config_; }
  std::uint64_t rejected_commands() const noexcept { return device_status().refused.total(); }
  TimeNs command_timeout() const noexcept { return contract().command_timeout; }
  // What the simulated motors apply now (N): the safe output is zero.
  Eigen::Vector3d applied_force() const noexcept { return applied_; }
  // What the virtual wall pushes on the tip now (N).
  Eigen::Vector3d wall_force() const noexcept { return to_eigen(wall_force_); }
  // Work done on the arm since start (J) by its motors, the hand and the wall.
  double servo_work() const noexcept { return servo_work_; }
  double hand_work() const noexcept { return hand_work_; }
  double wall_work() const noexcept { return wall_work_; }
  // Times the hardware was put in its safe state (disable, fault, stop, failed start).
  int safe_entries() const noexcept { return safe_entries_; }

  struct Columns {
    StateColumn<Pose> measured_cp;
    StateColumn<Twist> measured_cv;
    StateColumn<JointState> measured_js;
    StateColumn<Vec3> hand_force, servo_force, wall_force;
    StateColumn<double> servo_work, hand_work, wall_work;
    StateColumn<bool> command_timeout;
    StateColumn<std::uint64_t> watchdog_trips;
  };
  const Columns& columns() const noexcept { return columns_; }

 protected:
  Outcome read() override;
  Outcome write(const Setpoint& s) override;
  void enter_safe_state(SafeReason) override;

 private:
  SimHapticDevice(std::string name, TaskConfig task, Checked<SimDeviceConfig> config);
  void set_button(std::uint8_t id, bool pressed) noexcept;
  void integrate(double dt, const Eigen::Vector3d& force, const Eigen::Vector3d& hand_target) noexcept;
  void publish() noexcept;
  Eigen::Vector3d wall(const Eigen::Vector3d& x, const Eigen::Vector3d& xd) const noexcept;
  void publish_stylus(double dt) noexcept;

  SimDeviceConfig config_;
  ArmKinematics kinematics_;
  Eigen::Vector3d q_, qd_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d applied_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_origin_ = Eigen::Vector3d::Zero(), hand_target_ = Eigen::Vector3d::Zero();
  TimeNs t0_ = -1;
  std::size_t hand_cursor_ = 0;
  bool hand_clutch_ = false;
  HandSample hand_{};                                           // this cycle's
  Eigen::Vector3d gimbal_ = Eigen::Vector3d::Zero();            // the stylus's sensed angles
  Eigen::Quaterniond stylus_ = Eigen::Quaterniond::Identity();  // its orientation (base frame)
  JointState grip_{};                                           // gripper_measured_js
  int safe_entries_ = 0;

  // State-table sources.
  Vec3 hand_force_{}, servo_force_{}, wall_force_{};
  Wrench contact_{};  // measured_cf: the wall's force on the tip, as a force sensor there reads it
  double servo_work_ = 0, hand_work_ = 0, wall_work_ = 0;
  std::uint64_t rejected_column_ = 0;
  Columns columns_;
};

}  // namespace saw::drivers
