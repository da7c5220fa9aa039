// PassivityPort: the master's end of a bilateral teleoperation network — the device's port, with
// its energy observed and the passivity controller acting where the device is.
#pragma once

#include <cstdint>
#include <limits>

#include "saw/crtk_arm.hpp"
#include "saw/task.hpp"
#include "saw/teleop/passivity.hpp"

namespace saw::teleop {

// What a port adds to the arm interface it re-publishes: the energy bookkeeping that crosses the
// link beside positions and forces (time-domain passivity needs each port's input energy at the
// other port).
namespace port {
// J: the energy that has entered the network at this port so far (only grows).
inline constexpr crtk::Read<double> energy{"port_energy"};
// J: the other port's input energy, as it arrived here (late: that is what keeps it passive).
inline constexpr crtk::Write<double> remote_energy{"port_remote_energy"};
// The wave variables of the port (scheme `wave`): u leaving (with the positions), v arriving.
inline constexpr crtk::Read<Vec3> wave{"port_wave"};
inline constexpr crtk::Write<Vec3> remote_wave{"port_remote_wave"};
// N·s/m: the wave impedance b the port runs with (scheme `wave`), 0 when it runs time-domain
// passivity. Fixed by the deployment and readable before the port's first cycle (no row needed):
// a wave law checks its own b against it at start-up (the two ends of a wave channel must share b).
inline constexpr crtk::Read<double> wave_impedance{"port_wave_impedance"};
}  // namespace port

// How the port keeps the network passive: time-domain passivity on the forces it is sent, or wave
// variables (the force made here from the returning wave and the device's velocity).
enum class PortScheme { passivity, wave };

struct PortConfig {
  PortScheme scheme = PortScheme::passivity;
  bool passivity = true;      // false: observe only (the paper's law, measured)
  double wave_impedance = 2;  // N·s/m, b of the wave scheme (the law's must be the same)
  double force_limit = 3;     // N: the most the wave scheme applies (the law limits its own)
  // N·s/m: the most the controller adds; none by default (its force is bounded by the law's).
  double max_damping = std::numeric_limits<double>::infinity();
  TimeNs command_hold = 0;  // how long a force is applied without a new one (0: 5 periods)
};

// Required "device" (CRTK arm: measured_cp, measured_cv, servo_cf; clutch and operator_present
// passed through), provided "arm" with the same names plus the port's own (namespace port).
// Each cycle it reads the device, publishes its position and velocity stamped with the device's
// row time (a dead device shows stale through this task), and applies the newest force command
// through the passivity controller with the device's velocity of this very cycle: the port gives
// the device no more energy than has entered at the other port. A command is applied for at most
// command_hold; after that the task writes nothing and the device's own watchdog takes it to its
// safe state. Commands and remote energies that are not finite (or negative) are refused, counted.
// With the wave scheme the force is the wave transform's (wave.hpp), from the device's velocity and
// the wave that arrived this cycle (none: zero, so a lost packet carries no energy); servo_cf is
// then ignored, and a port that has had no wave for command_hold writes nothing.
class PassivityPort : public Task {
 public:
  PassivityPort(std::string name, TaskConfig task, PortConfig config);

  void run() override;

  const PassivityController& controller() const noexcept { return pc_; }
  std::uint64_t rejected() const noexcept { return rejected_; }

 private:
  void on_command(const Wrench& w) noexcept;
  void on_remote_energy(double e) noexcept;
  void on_remote_wave(const Vec3& v) noexcept;
  void apply_passivity(const Eigen::Vector3d& velocity, double dt) noexcept;
  void apply_wave(const Eigen::Vector3d& velocity) noexcept;

  PortConfig config_;
  PassivityController pc_;
  double remote_in_ = 0;
  Wrench pending_{};
  bool has_pending_ = false;
  Eigen::Vector3d pending_wave_ = Eigen::Vector3d::Zero();
  bool has_wave_ = false;
  Eigen::Vector3d held_ = Eigen::Vector3d::Zero();
  TimeNs held_since_ = -1;
  TimeNs device_time_ = 0;  // of the last good reading
  std::uint64_t rejected_ = 0;

  // State-table sources.
  Pose cp_{};
  Twist cv_{};
  double energy_in_ = 0, energy_out_ = 0, dissipated_ = 0, damping_ = 0, remote_shown_ = 0;
  Vec3 applied_{}, wave_out_{};

  FunctionRead<Pose> read_cp_;
  FunctionRead<Twist> read_cv_;
  FunctionWrite<Wrench> write_cf_;
  EventWrite<ButtonEvent>* clutch_ = nullptr;
  EventWrite<ButtonEvent>* operator_present_ = nullptr;
};

}  // namespace saw::teleop
