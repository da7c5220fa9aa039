// Law: what a teleoperation control law is to the teleoperation task that runs it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <concepts>
#include <cstdint>
#include <limits>
#include <string_view>
#include <tuple>

#include "saw/clock.hpp"
#include "saw/teleop/fault_info.hpp"
#include "saw/teleop/law_input.hpp"
#include "saw/teleop/law_output.hpp"

namespace saw::teleop {

// One device as the task read it this cycle: its last good sample, checked finite.
struct SideSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // m/s
  TimeNs age = 0;                                      // ns since the sample was taken (delay included)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // a unit quaternion, checked
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();       // rad/s
  // The master's gripper or the slave's jaw (rad), checked finite; NaN: the device has none.
  double grip = std::numeric_limits<double>::quiet_NaN();
};

// What the task gives a law every cycle it drives the devices, or holds them.
struct LawInputs {
  SideSample master, slave;
  double period = 0.001;  // s, the task's
  // What the law declared it needs besides these (declared_inputs), in declaration order:
  // in.declared.get<Wrench>(0) — each checked valid, the last good one while a read fails;
  // in.declared.fresh(0) — read with this cycle's new row. A passivity port's energy or wave is
  // one of these.
  DeclaredInputs declared{};
  // What the law declared it sends (declared_outputs): in.outputs.set(0, energy) in step() sends
  // it this cycle, before the forces.
  DeclaredOutputs outputs{};
};

// What a law answers: the forces to send, and what it shows of itself. The task checks the
// forces finite again before any device sees them.
struct LawCommand {
  Eigen::Vector3d master_force = Eigen::Vector3d::Zero();  // N (zero: the master feels nothing)
  Eigen::Vector3d slave_force = Eigen::Vector3d::Zero();   // N
  // The tracking errors the law works on (e_m, e_s); |e_s| is the task's tracking figure.
  Eigen::Vector3d master_error = Eigen::Vector3d::Zero(), slave_error = Eigen::Vector3d::Zero();
  Eigen::Vector3d slave_offset = Eigen::Vector3d::Zero();  // m, where the slave's goal sits
  bool limiting = false;                                   // a force is held at its limit (the ratchet slips)
  // For a law that `gives_slave_goal`: where the slave should be (m), for a slave that follows a
  // pose (servo_cp, a PSM) rather than a force; slave_force is then not sent.
  Eigen::Vector3d slave_goal = Eigen::Vector3d::Zero();
  // With orients_slave, the slave's goal orientation (a unit quaternion) with slave_goal; without
  // it the task holds the slave's orientation from the engagement.
  Eigen::Quaterniond slave_goal_orientation = Eigen::Quaterniond::Identity();
  bool orients_slave = false;
  // The slave's jaw goal (rad), sent to a slave that has a jaw; NaN: none.
  double slave_jaw = std::numeric_limits<double>::quiet_NaN();
  // The law moves the master itself (a move_cp it sent, not yet under way or done): no wrench
  // goes to the master this cycle, for a servo command would pre-empt the move.
  bool master_moving = false;
  // False when the law's arithmetic overflowed (a huge input): the task then faults with zero
  // force, naming `bad_side`.
  bool finite = true;
  FaultSide bad_side = FaultSide::none;
};

// Built once, outside the RT path, for the task that will run the law.
struct LawContext {
  double period = 0.001;  // s
};

// A control law is a value type:
//   struct MyLaw {
//     static constexpr std::string_view name = "my_law", description = "one line";
//     struct Settings { double gain = 1; ... };           // plain, defaults are the defaults
//     static constexpr auto declared_settings = std::tuple{Setting<Settings, double>{...}, ...};
//     MyLaw(const Settings&, const LawContext&);
//     Settings& settings() noexcept;                        // read back, and written by set_<name>
//     void reset(const LawInputs&) noexcept;   // (re-)engaging this cycle: start without a force step
//     LawCommand step(const LawInputs&) noexcept;  // one engaged cycle
//   };
// and optionally
//     void hold(const LawInputs&) noexcept;    // the task drives nothing (disabled, clutch, busy
//                                              // device): stay ready to engage (default: reset)
//     void on_set(std::string_view setting, const Settings& before) noexcept;  // after set_<name>
//     std::uint64_t refusals() const noexcept; int last_refusal() const noexcept;  // e.g. a planner's
//     static constexpr auto declared_readouts = std::tuple{Readout<MyLaw, double>{...}, ...};
//                                              // values it computes, shown as the task's state
//     static constexpr bool gives_slave_goal = true;  // sets LawCommand::slave_goal: it can drive
//                                              // a slave that follows a pose (slave_command: servo_cp)
//     static constexpr bool gives_no_force = true;  // and only such a slave
//     static constexpr auto declared_inputs = std::tuple{Input<Wrench>{LawSide::slave, "measured_cf"}};
//                                              // read commands of either device it needs, by name
//                                              // and type (law_input.hpp): no task edit for a new one;
//                                              // one may have to agree with a setting (a wave port's b)
//     static constexpr auto declared_outputs = std::tuple{Output<double>{LawSide::master,
//     "port_remote_energy"}};
//                                              // write commands it sends to (law_output.hpp): a
//                                              // passive law's energy or wave, through its port
// step, reset, hold and on_set run in the RT thread: they allocate, lock, block and throw nothing.
template <class L>
concept Law = requires(L law, const LawInputs& in) {
  { L::name } -> std::convertible_to<std::string_view>;
  { L::description } -> std::convertible_to<std::string_view>;
  typename L::Settings;
  L::declared_settings;
  requires std::constructible_from<L, const typename L::Settings&, const LawContext&>;
  { law.settings() } -> std::same_as<typename L::Settings&>;
  { law.reset(in) }
  noexcept;
  { law.step(in) }
  noexcept->std::same_as<LawCommand>;
};

}  // namespace saw::teleop
