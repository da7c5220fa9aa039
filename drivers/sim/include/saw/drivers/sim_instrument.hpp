// SimInstrument: a simulated PSM-like instrument arm with a wrist and a jaw, taking poses, as a periodic
// task.
#pragma once

#include <cstdint>
#include <string_view>

#include "saw/device.hpp"
#include "saw/drivers/instrument_kinematics.hpp"

namespace saw::drivers {

struct SimInstrumentConfig {
  // The base's settings: servo_cp within the workspace (m, the base frame at the remote centre)
  // and no faster than the speeds from the last accepted pose; the safe state holds.
  DeviceSettings contract{.max_linear_speed = 0.2, .max_angular_speed = 3.0};
  InstrumentKinematics::Joints initial_joints =
      (InstrumentKinematics::Joints() << 0, 0, 0.1, 0, 0, 0).finished();
  // The joints' stops (rad, m) and fastest motion (rad/s, m/s), of the order of a PSM's.
  InstrumentKinematics::Joints joint_min =
      (InstrumentKinematics::Joints() << -1.6, -0.87, 0.0, -4.5, -1.4, -1.4).finished();
  InstrumentKinematics::Joints joint_max =
      (InstrumentKinematics::Joints() << 1.6, 0.87, 0.24, 4.5, 1.4, 1.4).finished();
  InstrumentKinematics::Joints max_velocity =
      (InstrumentKinematics::Joints() << 1, 1, 0.2, 8, 8, 8).finished();
  // The joints' servo: each follows its setpoint as a first-order lag of this time constant (s).
  double servo_lag = 0.005;
  // The jaw (rad): jaw_servo_jp goals within [jaw_min, jaw_max] (others refused), followed at
  // no more than jaw_rate through the same lag.
  double jaw_min = -0.35, jaw_max = 1.4, jaw_rate = 4.0, initial_jaw = 0.0;
};

// What a run of it comes to (the "summary" column).
struct SimInstrumentSummary {
  static constexpr std::string_view type_name = "saw::drivers::SimInstrumentSummary";
  static constexpr std::uint32_t layout_version = 1;
  std::uint64_t poses = 0;        // servo_cp goals followed
  std::uint64_t unreachable = 0;  // goals its joints could not reach (held at the closest)
  std::uint64_t jaw_goals = 0, jaw_refused = 0;
  static constexpr auto fields =
      std::tuple{&SimInstrumentSummary::poses, &SimInstrumentSummary::unreachable,
                 &SimInstrumentSummary::jaw_goals, &SimInstrumentSummary::jaw_refused};
};

// Provided "arm" (CRTK, by the device base): measured_cp/cv, measured_js (its six joints),
// operating_state, fault, command_timeout, watchdog_trips (reads); servo_cp, state_command
// (writes); and jaw_measured_js, jaw_servo_jp. Each servo_cp the base accepted is solved for the
// joints (damped least squares from the last setpoint), whose setpoints move toward it no faster
// than max_velocity; the joints follow with servo_lag. Commands stopping, disable and faults
// hold it where it is.
class SimInstrument : public Device {
 public:
  SimInstrument(std::string name, TaskConfig task, SimInstrumentConfig config);

  const SimInstrumentSummary& summary() const noexcept { return summary_; }

 protected:
  Outcome read() override;
  Outcome write(const Setpoint& s) override;
  void enter_safe_state(SafeReason) override;

 private:
  SimInstrument(std::string name, TaskConfig task, Checked<SimInstrumentConfig> config);
  void on_jaw(const JointState& j) noexcept;
  void publish(double dt) noexcept;

  SimInstrumentConfig config_;
  InstrumentKinematics kinematics_;
  InstrumentKinematics::Joints q_, setpoint_, solved_;  // measured, servo setpoint, last IK answer
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  double jaw_ = 0, jaw_setpoint_ = 0, jaw_goal_ = 0;
  JointState jaw_js_{};
  SimInstrumentSummary summary_{};
};

}  // namespace saw::drivers
