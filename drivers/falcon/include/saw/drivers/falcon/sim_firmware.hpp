// SimFalconFirmware: a simulated Falcon (firmware, motors, delta arms, operator's hand) speaking
// the real packet format, and SimTransport, which puts it behind the FalconTransport seam. Its
// side of the wire is its own, written from libnifalcon's description (not packet.cpp), so a
// mistake in the driver's codec shows instead of cancelling out.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>

#include "saw/drivers/falcon/delta_dynamics.hpp"
#include "saw/drivers/falcon/delta_kinematics.hpp"
#include "saw/drivers/falcon/transport.hpp"

namespace saw::drivers::falcon {

struct SimFirmwareConfig {
  DeltaGeometry geometry;
  double dt = 1e-3;  // s simulated per exchange (the driver's period)
  int substeps = 4;
  double inertia = DeltaArmDynamics{}.inertia;  // kg·m² per arm (with the motor's, through the capstan)
  double damping = DeltaArmDynamics{}.damping;  // N·m·s/rad per arm
  Eigen::Vector3d initial_angles = Eigen::Vector3d::Constant(0.7);  // rad
  double angle_min = DeltaArmDynamics{}.angle_min;                  // rad: the arms' mechanical stops
  double angle_max = DeltaArmDynamics{}.angle_max;
  // Until homed the encoders count from where the arms were at power-up: this far off.
  std::array<std::int16_t, 3> power_up_offset{123, -456, 789};
  double index_angle = 0.3;  // rad: an arm passing this going up in homing mode is homed
  // The operator homes by hand, as libnifalcon tells users to: while the firmware is in homing
  // mode and not homed, the hand pulls the grip all the way out for gesture_out s, then pushes
  // it in (the arms up past their index), and again until homed. Off: only a motor push homes.
  bool operator_homes = true;
  double gesture_out = 0.1;  // s
  // The operator's hand (once homed): a spring-damper pulling the grip to origin + a sinusoid.
  bool hand = false;
  Eigen::Vector3d hand_amplitude = Eigen::Vector3d::Zero();  // m
  double hand_frequency = 0.5;                               // Hz
  double hand_stiffness = 200, hand_damping = 2;             // N/m, N·s/m
};

// What the LEDs show, decoded from the control nibble with libnifalcon's enum (FalconFirmware.h:
// green 0x2, blue 0x4, red 0x8).
enum class SimLed : std::uint8_t { off, green, blue, red, several };

class SimFalconFirmware {
 public:
  explicit SimFalconFirmware(SimFirmwareConfig c = {});

  // One exchange: decodes the command (a corrupt one is ignored: zero torque, as the real
  // firmware's watchdog would), steps the dynamics by dt and answers with a report.
  Packet answer(const Packet& command) noexcept;

  // Scripting (test or deployment thread between exchanges; not thread-safe).
  void set_buttons(std::uint8_t b) noexcept { buttons_ = b & status::buttons; }
  void set_hand_target(const Eigen::Vector3d& offset) noexcept { hand_offset_ = offset; }  // from origin
  void set_hand(bool on) noexcept { config_.hand = on; }
  void drop_answers(int n) noexcept { drop_ = n; }        // the next n exchanges get no answer
  void corrupt_answers(int n) noexcept { corrupt_ = n; }  // the next n answers have a bad byte
  void unplug() noexcept { unplugged_ = true; }
  // The firmware stops reporting the arms homed (what a glitch, or a dropped homing bit, does):
  // the operator must home again.
  void lose_homing() noexcept { homed_ = {}; }

  bool unplugged() const noexcept { return unplugged_; }
  bool dropping() noexcept { return drop_ > 0 ? (--drop_, true) : false; }
  const Eigen::Vector3d& angles() const noexcept { return theta_; }
  Eigen::Vector3d tip() const noexcept;
  Eigen::Vector3d hand_force() const noexcept { return hand_force_; }
  SimLed led() const noexcept;
  bool homing_mode() const noexcept;  // the last command had the homing bit
  bool homed(int i) const noexcept { return homed_[static_cast<std::size_t>(i)]; }
  Eigen::Vector3d motor_torque() const noexcept { return torque_; }
  std::uint64_t commands_refused() const noexcept { return refused_; }
  double time() const noexcept { return t_; }

 private:
  void step(double dt) noexcept;

  SimFirmwareConfig config_;
  DeltaKinematics kinematics_;
  Eigen::Vector3d theta_, theta_dot_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_ = Eigen::Vector3d::Zero(), hand_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d origin_, hand_offset_ = Eigen::Vector3d::Zero();
  std::array<bool, 3> homed_{};     // reported homed (in homing mode)
  std::array<bool, 3> absolute_{};  // counts from the index (homed once): kept when homing is lost
  double gesture_t_ = 0;            // s into the operator's homing gesture
  Eigen::Vector3d pulled_out_, pushed_in_;
  Eigen::Vector3d tip_ = Eigen::Vector3d::Constant(NAN);  // the last step's tip (forward's seed)
  std::uint8_t control_ = 0, buttons_ = 0;
  int drop_ = 0, corrupt_ = 0;
  bool unplugged_ = false;
  std::uint64_t refused_ = 0;
  double t_ = 0;
};

// The simulated firmware behind the seam: an exchange is one answer(), in the caller's thread.
class SimTransport final : public FalconTransport {
 public:
  explicit SimTransport(SimFirmwareConfig c = {}) : firmware_(std::make_unique<SimFalconFirmware>(c)) {}
  void open() override { open_ = true; }
  ExchangeResult exchange(const Packet& out, Packet& in) noexcept override;
  void close() noexcept override { open_ = false; }
  std::string describe() const override { return "simulated Falcon firmware"; }
  SimFalconFirmware& firmware() noexcept { return *firmware_; }

 private:
  std::unique_ptr<SimFalconFirmware> firmware_;
  bool open_ = false;
};

}  // namespace saw::drivers::falcon
