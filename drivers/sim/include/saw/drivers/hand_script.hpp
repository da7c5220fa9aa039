// HandScript: a scripted operator's hand that drags a simulated device through a virtual spring.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace saw::drivers {

struct HandSample {
  double t = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool clutch = false;
  double turn = 0;  // rad about HandScript::turn_axis (a stylus's hand)
  double grip = 0;  // rad, the gripper's angle
};

// Target positions are relative to the device's initial tip position (the hand's origin).
struct HandScript {
  enum class Kind : std::uint8_t { none, line, sinusoid, csv, reach } kind = Kind::none;
  double stiffness = 200.0;  // N/m
  double damping = 2.0;      // N·s/m
  // line: from `from` to `to` in `duration` s, then hold (or back and forth).
  Eigen::Vector3d from = Eigen::Vector3d::Zero(), to = Eigen::Vector3d::Zero();
  double duration = 1.0;
  bool back_and_forth = false;
  // sinusoid: amplitude·sin(2π·frequency·t + phase)
  Eigen::Vector3d amplitude = Eigen::Vector3d::Zero();
  double frequency = 0.5, phase = 0.0;
  // csv: "t,x,y,z[,clutch]" rows, loaded by load_csv() (not on an RT path).
  std::vector<HandSample> samples;
  // reach: as a person moves between targets: from the origin to each target in turn and back
  // to the origin, each reach a minimum-jerk profile of `reach_time` s (Flash & Hogan: the
  // smoothest path, zero velocity and acceleration at both ends), then still for `dwell` s.
  std::vector<Eigen::Vector3d> targets;
  double reach_time = 1.0, dwell = 0.5;
  // Physiological tremor on top of any motion: three sinusoids near `tremor_frequency` (one per
  // axis, 8–12 Hz in a person), each of `tremor_amplitude` m peak (sub-millimetre in a person).
  double tremor_amplitude = 0.0, tremor_frequency = 10.0;
  // A stylus in the hand (SimDeviceConfig::stylus): it turns about `turn_axis` (the base's frame)
  // by turn_amplitude·sin(2π·frequency·t + phase) and squeezes the gripper to
  // grip_mean + grip_amplitude·sin(2π·frequency·t + phase), whatever the position's kind.
  Eigen::Vector3d turn_axis = Eigen::Vector3d::UnitZ();
  double turn_amplitude = 0.0;                   // rad
  double grip_mean = 0.0, grip_amplitude = 0.0;  // rad
  // The operator presses the clutch from the first to the second time of each window (s since
  // the first cycle), whatever the kind (csv rows carry their own clutch column).
  std::vector<std::pair<double, double>> clutch_windows;

  // Throws std::runtime_error naming the file and line of a bad row.
  static std::vector<HandSample> load_csv(const std::string& path);

  // The target at time t (s since the first cycle); `cursor` keeps CSV lookups O(1) per cycle.
  HandSample target(double t, std::size_t& cursor) const noexcept;
};

}  // namespace saw::drivers
