// DelayTask: re-publishes a device's CRTK state as it was `delay` ago, to simulate a network.
#pragma once

#include "saw/crtk_arm.hpp"
#include "saw/description.hpp"
#include "saw/task.hpp"
#include "saw/teleop/delay_channel.hpp"
#include "saw/teleop/passivity_port.hpp"

namespace saw::teleop {

// One reading of the source as it travels.
struct DelayedSample {
  Pose cp{};
  Twist cv{};
  TimeNs source_time = 0;
  double port_energy = -1;  // J, the source port's input energy; -1: the source has no port
  Vec3 port_wave{};         // the source port's outgoing wave (scheme wave)
};

// One force command as it travels, with the energy bookkeeping of a passive network beside it.
struct DelayedCommand {
  Wrench wrench{};
  double remote_energy = -1;  // J, for the device's port; -1: none sent
  Vec3 remote_wave{};         // for the device's port, when has_wave
  bool has_wave = false;
  double port_b = 0;  // N·s/m: the port's wave_impedance when the wave was sent (NaN: not known)
};

// What a DelayTask adds to the arm interface it re-publishes; Teleoperation reads
// them, when present, to judge staleness on the source.

namespace delayed_arm {
inline constexpr crtk::Read<TimeNs> source_time{"source_time"};  // of the source row shown
inline constexpr crtk::Read<TimeNs> delay{"delay"};              // how late it is meant to be
}  // namespace delayed_arm

// A simulated network between a device and its controller: each direction its own link.
struct DelayConfig {
  LinkConfig measured;  // the device's measured_cp/cv on their way to the controller
  LinkConfig commands;  // servo_cf on its way to the device (all zero: passed straight through)
  // The device end repeats the last command that arrived, each cycle, for at most this long (0:
  // the commands link's jitter plus 5 periods): a lost or late packet is not a gap in the
  // device's command stream, and a controller that died is still noticed by the device's watchdog.
  TimeNs command_hold = 0;
};

// Required "source" (a device's arm interface), provided "arm" with the same CRTK names.
// Positions and velocities come out through the `measured` link (late, jittered, some lost: the
// newest arrived is shown and held); force commands through the `commands` link; button events
// pass through. A source that is a passivity port has its port_energy and port_wave carried with
// its positions, and port_remote_energy and port_remote_wave travel with the force commands (the
// same packets); its port_wave_impedance, a setting, is read through undelayed (disconnected when
// the source has none), and a wave is delivered only if the port still answers the b it answered
// when the wave was sent (a port restarted with another b meanwhile gets none of the old b's waves:
// dropped, counted); `description` (kind "delay") names the source. A wave is delivered once, in the cycle
// its packet arrives: a held (repeated) command carries none, since a repeated wave would bring energy that
// was never sent. The rows are this task's, stamped with its cycle: "source_time" says when the source wrote
// the value shown (it stops advancing when the source dies) and "delay" how late it is meant to be, so that a
// consumer can judge staleness on the source (the teleoperation does).
class DelayTask : public Task {
 public:
  DelayTask(std::string name, TaskConfig task, double delay_seconds);
  DelayTask(std::string name, TaskConfig task, DelayConfig config);

  void run() override;
  double delay() const noexcept { return static_cast<double>(delay_) * 1e-9; }
  const DelayChannel<DelayedSample>& measured_link() const noexcept { return measured_; }
  const DelayChannel<DelayedCommand>& commands_link() const noexcept { return commands_; }
  // Waves not delivered because the port's wave_impedance changed (or went unanswered) on the way.
  std::uint64_t waves_dropped() const noexcept { return waves_dropped_; }

 private:
  void pass_command(const Wrench& w) noexcept;
  void pass_energy(double e) noexcept;
  void pass_wave(const Vec3& w) noexcept;
  // The source's wave_impedance now; NaN when it does not answer (never equal to a sent one).
  double source_impedance() const noexcept;

  TimeNs delay_;
  bool commands_direct_;
  TimeNs command_hold_;
  Pose measured_cp_{};
  Twist measured_cv_{};
  TimeNs source_time_ = 0;  // of the row shown
  DelayChannel<DelayedSample> measured_;
  double port_energy_ = -1;    // shown, with the row shown
  double remote_energy_ = -1;  // the newest written, sent with the next command
  Vec3 port_wave_{};           // shown, with the row shown
  Vec3 remote_wave_{};         // the newest written, sent with the next command
  bool has_remote_wave_ = false;
  double remote_wave_b_ = 0;  // the source's b when remote_wave_ was written
  std::uint64_t waves_dropped_ = 0;
  DelayChannel<DelayedCommand> commands_;
  bool have_output_ = false;
  DelayedCommand held_{};
  TimeNs held_since_ = -1;  // when the held command arrived; -1: none
  FunctionRead<Pose> read_cp_;
  FunctionRead<Twist> read_cv_;
  FunctionWrite<Wrench> write_cf_;
  FunctionRead<double> read_energy_;
  FunctionWrite<double> write_remote_energy_;
  FunctionRead<Vec3> read_wave_;
  FunctionWrite<Vec3> write_remote_wave_;
  FunctionRead<double> read_impedance_;
  const RequiredInterface* source_ = nullptr;
  EventWrite<ButtonEvent>* clutch_ = nullptr;
  EventWrite<ButtonEvent>* operator_present_ = nullptr;
};

}  // namespace saw::teleop
