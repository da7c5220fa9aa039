// SimHapticDevice: a simulated 3-DOF force-feedback device (an Omni-like arm, a Falcon) as a periodic task.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "saw/command_watchdog.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/drivers/arm_kinematics.hpp"
#include "saw/drivers/hand_script.hpp"
#include "saw/task.hpp"

namespace saw::drivers {

struct SimDeviceConfig {
  ArmModel model = ArmModel::omni;
  // rad; zero: the model's default (Omni: elbow bent 1.2 rad; Falcon: every arm at 35°).
  Eigen::Vector3d initial_joints = Eigen::Vector3d::Zero();
  Eigen::Vector3d inertia = Eigen::Vector3d::Zero();  // zero: the model's default
  Eigen::Vector3d damping = Eigen::Vector3d::Zero();  // zero: the model's default
  Eigen::Vector3d joint_min = Eigen::Vector3d::Zero(),
                  joint_max = Eigen::Vector3d::Zero();  // equal: defaults
  double max_force = 0;  // N; zero: the model's default (Omni 3.3 N, Falcon 9 N)
  bool start_enabled = true;
  HandScript hand;
  int substeps = 4;  // integration steps per cycle
  // Command watchdog: with no fresh servo_cf for this long, the device applies zero force
  // (a dead teleoperation process must not leave it pushing). 0: 3 periods.
  TimeNs command_timeout = 0;
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

// What a run of the device comes to (its "summary" column, ColumnUse::summary).
struct SimDeviceSummary {
  static constexpr std::string_view type_name = "saw::drivers::SimDeviceSummary";
  static constexpr std::uint32_t layout_version = 1;
  std::uint64_t rejected_commands = 0;  // servo_cf not finite or over max_force
  std::uint64_t watchdog_trips = 0;     // times commands stopped coming and the force went to zero
  TimeNs command_timeout = 0;
};

// Provided "arm" (CRTK, crtk_arm.hpp): measured_cp, measured_cv, measured_js (with the model's
// joint names), operating_state (reads); servo_cf, state_command (writes); operating_state,
// clutch, operator_present (events).
// Provided "sim": set_button (write), hand_force, rejected_commands (reads).
// Also on "arm": servo_force (the force applied this cycle), command_timeout (true while the
// watchdog holds the force at zero), watchdog_trips (reads).
// A servo_cf that is not finite or exceeds max_force is rejected before it reaches the
// dynamics (the device then applies zero force) and counted. A servo_cf older than
// command_timeout is dropped: zero force until the next one.
class SimHapticDevice : public Task {
 public:
  SimHapticDevice(std::string name, TaskConfig task, SimDeviceConfig config);

  void run() override;
  const SimDeviceConfig& device_config() const noexcept { return config_; }
  std::uint64_t rejected_commands() const noexcept { return rejected_; }
  // Times the command watchdog dropped a force (each time commands stopped coming).
  std::uint64_t watchdog_trips() const noexcept { return watchdog_.trips(); }
  TimeNs command_timeout() const noexcept { return config_.command_timeout; }

  struct Columns {
    StateColumn<Pose> measured_cp;
    StateColumn<Twist> measured_cv;
    StateColumn<JointState> measured_js;
    StateColumn<Vec3> hand_force, servo_force;
    StateColumn<bool> command_timeout;
    StateColumn<std::uint64_t> watchdog_trips;
  };
  const Columns& columns() const noexcept { return columns_; }

 private:
  void servo_cf(const Wrench& w) noexcept;
  void state_command(StateCommand c) noexcept;
  void set_state(OperatingStateValue s) noexcept;
  void button(std::uint8_t id, bool pressed) noexcept;
  void integrate(double dt, const Eigen::Vector3d& hand_target) noexcept;
  void publish() noexcept;
  void watch_commands() noexcept;

  SimDeviceConfig config_;
  ArmKinematics kinematics_;
  Eigen::Vector3d q_, qd_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_ = Eigen::Vector3d::Zero();  // accepted servo_cf
  Eigen::Vector3d hand_origin_ = Eigen::Vector3d::Zero();
  TimeNs t0_ = -1;
  std::size_t hand_cursor_ = 0;
  bool hand_clutch_ = false;
  std::uint64_t rejected_ = 0;
  CommandWatchdog watchdog_{state_table()};  // servo_cf's

  // State-table sources.
  Pose measured_cp_{};
  Twist measured_cv_{};
  JointState measured_js_{};
  OperatingState operating_state_{};
  Vec3 hand_force_{}, servo_force_{};
  std::uint64_t rejected_column_ = 0;
  SimDeviceSummary summary_{};
  Columns columns_;

  EventWrite<OperatingState>* state_event_ = nullptr;
  EventWrite<ButtonEvent>* clutch_event_ = nullptr;
  EventWrite<ButtonEvent>* operator_event_ = nullptr;
};

}  // namespace saw::drivers
