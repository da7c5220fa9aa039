#include "saw/drivers/falcon/sim_firmware.hpp"

#include <cmath>
#include <numbers>

namespace saw::drivers::falcon {
namespace {

// The firmware's side of the wire from libnifalcon's description (FalconFirmwareNovintSDK.h/.cpp,
// FalconFirmware.h; tests/falcon/reference/README.md), deliberately not packet.cpp: 16 bytes,
// '<' (0x3c), 14 bytes of 0x41 + a value, '>' (0x3e); three 16-bit words of 4 nibbles each, least
// significant first, in bytes 1..12; byte 13 the control nibble (host) or the status (device);
// byte 14 unused ('A').
namespace wire {
constexpr std::uint8_t open = 0x3c, close = 0x3e, zero = 0x41;
constexpr std::uint8_t homing = 0x01, green = 0x02, blue = 0x04, red = 0x08;
constexpr unsigned homed_bit0 = 0x10;  // status: arm i homed = 0x10 << i (only in homing mode)

bool decode_command(const Packet& p, std::array<std::int16_t, 3>& dac, std::uint8_t& control) noexcept {
  if (p[0] != open || p[15] != close) return false;
  for (std::size_t k = 1; k <= 13; ++k)
    if (p[k] < zero || p[k] > zero + 0xf) return false;
  for (std::size_t w = 0; w < 3; ++w) {
    unsigned v = 0;
    for (std::size_t k = 0; k < 4; ++k) v |= static_cast<unsigned>(p[1 + 4 * w + k] - zero) << (4 * k);
    dac[w] = static_cast<std::int16_t>(static_cast<std::uint16_t>(v));
  }
  control = static_cast<std::uint8_t>(p[13] - zero);
  return true;
}

Packet encode_report(const std::array<std::int16_t, 3>& encoder, unsigned status) noexcept {
  Packet p{};
  p[0] = open;
  for (std::size_t w = 0; w < 3; ++w) {
    const auto v = static_cast<std::uint16_t>(encoder[w]);
    for (std::size_t k = 0; k < 4; ++k)
      p[1 + 4 * w + k] = static_cast<std::uint8_t>(zero + ((v >> (4 * k)) & 0xf));
  }
  p[13] = static_cast<std::uint8_t>(zero + (status & 0x7f));
  p[14] = zero;
  p[15] = close;
  return p;
}
}  // namespace wire

}  // namespace

SimFalconFirmware::SimFalconFirmware(SimFirmwareConfig c)
    : config_(c), kinematics_(c.geometry), theta_(c.initial_angles) {
  origin_ = tip();
  // Where the operator's gesture takes the grip: past the arms' stops either way.
  pulled_out_ = pushed_in_ = origin_;
  (void)kinematics_.forward(Eigen::Vector3d::Constant(c.angle_max + 0.1), pulled_out_);
  (void)kinematics_.forward(Eigen::Vector3d::Constant(c.angle_min - 0.1), pushed_in_);
}

SimLed SimFalconFirmware::led() const noexcept {
  switch (control_ & (wire::green | wire::blue | wire::red)) {
    case 0:
      return SimLed::off;
    case wire::green:
      return SimLed::green;
    case wire::blue:
      return SimLed::blue;
    case wire::red:
      return SimLed::red;
    default:
      return SimLed::several;
  }
}

bool SimFalconFirmware::homing_mode() const noexcept { return control_ & wire::homing; }

Eigen::Vector3d SimFalconFirmware::tip() const noexcept {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  (void)kinematics_.forward(theta_, x, tip_);
  return x;
}

void SimFalconFirmware::step(double dt) noexcept {
  const double t = t_;
  Eigen::Vector3d target = origin_ + hand_offset_;
  if (config_.hand)
    target += config_.hand_amplitude * std::sin(2 * std::numbers::pi * config_.hand_frequency * t);
  Eigen::Vector3d x;
  Eigen::Matrix3d j;
  if (kinematics_.forward(theta_, x, tip_) && kinematics_.jacobian(theta_, x, j))
    tip_ = x;  // the next step's seed
  else
    j.setZero();
  const Eigen::Vector3d xd = j * theta_dot_;
  const bool homed = homed_[0] && homed_[1] && homed_[2];
  const bool gesture = config_.operator_homes && homing_mode() && !homed;
  // The simulated operator takes the grip once the Falcon has homed, or to home it by hand.
  const bool held = homed && (config_.hand || !hand_offset_.isZero());
  if (gesture) {
    const bool out = std::fmod(gesture_t_, 2 * config_.gesture_out) < config_.gesture_out;
    hand_force_ = config_.hand_stiffness * ((out ? pulled_out_ : pushed_in_) - x) - config_.hand_damping * xd;
    gesture_t_ += dt;
  } else {
    gesture_t_ = 0;
    hand_force_ = held ? Eigen::Vector3d(config_.hand_stiffness * (target - x) - config_.hand_damping * xd)
                       : Eigen::Vector3d::Zero();
  }
  const Eigen::Vector3d tau = torque_ + j.transpose() * hand_force_ - config_.damping * theta_dot_;
  theta_dot_ += dt * tau / config_.inertia;  // semi-implicit Euler
  const Eigen::Vector3d before = theta_;
  theta_ += dt * theta_dot_;
  for (int i = 0; i < 3; ++i) {  // the mechanical stops
    if (theta_[i] < config_.angle_min)
      theta_[i] = config_.angle_min, theta_dot_[i] = std::max(0.0, theta_dot_[i]);
    if (theta_[i] > config_.angle_max)
      theta_[i] = config_.angle_max, theta_dot_[i] = std::min(0.0, theta_dot_[i]);
    const auto k = static_cast<std::size_t>(i);
    // The index is an edge: passed going up (the grip pushed in), not merely lying beyond it.
    if (homing_mode() && before[i] > config_.index_angle && theta_[i] <= config_.index_angle)
      homed_[k] = absolute_[k] = true;
  }
  t_ += dt;
}

Packet SimFalconFirmware::answer(const Packet& command) noexcept {
  std::array<std::int16_t, 3> dac{};
  std::uint8_t control = 0;
  if (wire::decode_command(command, dac, control)) {
    control_ = control;
    torque_ = kinematics_.torque(dac);
  } else {
    ++refused_;
    torque_.setZero();
  }
  // Homed only while the host keeps the homing bit set (libnifalcon: "must be set in every
  // packet"); what the real firmware does with the counts then is unknown: they are kept.
  if (!homing_mode()) homed_ = {};
  const double h = config_.dt / config_.substeps;
  for (int s = 0; s < config_.substeps; ++s) step(h);
  std::array<std::int16_t, 3> encoder{};
  unsigned status = buttons_;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::int16_t e = kinematics_.encoder(theta_[static_cast<Eigen::Index>(i)]);
    encoder[i] = absolute_[i] ? e : static_cast<std::int16_t>(e - config_.power_up_offset[i]);
    if (homing_mode() && homed_[i]) status |= wire::homed_bit0 << i;
  }
  Packet p = wire::encode_report(encoder, status);
  if (corrupt_ > 0) --corrupt_, p[7] = 'Z';
  return p;
}

ExchangeResult SimTransport::exchange(const Packet& out, Packet& in) noexcept {
  if (!open_ || firmware_->unplugged()) return {ExchangeStatus::disconnected, 0, 0};
  in = firmware_->answer(out);  // time passes for the arms whether or not the answer arrives
  if (firmware_->dropping()) return {ExchangeStatus::no_answer, 0, 0};
  return {ExchangeStatus::ok, packet_size, 0};
}

}  // namespace saw::drivers::falcon
