#include "saw/drivers/falcon/falcon_device.hpp"

#include <cmath>
#include <span>
#include <stdexcept>

#include "saw/eigen.hpp"

namespace saw::drivers::falcon {
namespace {

// The contract's settings are the base's to check (Device's constructor).
FalconConfig checked(FalconConfig c) {
  if (!(c.contract.max_force > 0)) throw std::invalid_argument("max_force must be positive");
  if (c.max_missed < 1) throw std::invalid_argument("max_missed must be at least 1");
  if (!(c.velocity_filter > 0 && c.velocity_filter <= 1))
    throw std::invalid_argument("velocity_filter in (0, 1]");
  return c;
}

// The contract the base runs for it: a haptic device, safe at zero force.
DeviceConfig contract_of(const FalconConfig& c) {
  DeviceConfig d;
  d.settings() = c.contract;
  d.safe_state = SafeState::zero_force;
  for (const char* n : {"arm0", "arm1", "arm2"}) d.joints.push_back(JointLimits{n});
  return d;
}

constexpr std::uint8_t leds_of(OperatingStateValue s, bool homing, bool homed) noexcept {
  if (s == OperatingStateValue::fault) return control::led_red;
  if (homing) return control::led_blue;
  if (s == OperatingStateValue::enabled && homed) return control::led_green;
  return 0;
}

}  // namespace

FalconDevice::FalconDevice(std::string name, TaskConfig task, FalconConfig config,
                           std::unique_ptr<FalconTransport> transport)
    : FalconDevice(std::move(name), task, Checked<FalconConfig>{checked(std::move(config))},
                   std::move(transport)) {}

FalconDevice::FalconDevice(std::string name, TaskConfig task, Checked<FalconConfig> config,
                           std::unique_ptr<FalconTransport> transport)
    : Device(std::move(name), task, contract_of(config.value)),
      config_(std::move(config.value)),
      kinematics_(config_.geometry),
      transport_(std::move(transport)) {
  if (!transport_) throw std::invalid_argument("FalconDevice '" + this->name() + "': no transport");
  origin_ = config_.origin;
  if (!origin_.allFinite() && !kinematics_.forward(kinematics_.angles({0, 0, 0}), origin_))
    throw std::invalid_argument("FalconDevice: the geometry has no pose at encoder counts 0");
  x_ = origin_;
  publish();

  auto& st = state_table();
  crtk_interface().add_command_read("servo_force", st.add_column("servo_force", &servo_force_));
  auto& falcon = provide("falcon");
  falcon.add_command_read("summary", st.add_column("summary", &summary_, ColumnUse::summary));
  falcon.add_command_read("leds", st.add_column("leds", &leds_));
}

FalconDevice::~FalconDevice() = default;

void FalconDevice::open() {
  transport_->open();  // throws TransportError saying what is wrong: the start fails with it
  // Busy while homing, as after a `home` command: a teleoperation holds until the positions are
  // absolute (before, they count from wherever the arms were at power-up).
  if (config_.home_on_start) start_homing();
}

void FalconDevice::close() noexcept { transport_->close(); }

Outcome FalconDevice::enable() {
  // Refused at once, saying why: enabled on nothing, it would go ENABLED (homing) and fault only
  // after max_missed cycles, as "no answer".
  if (!transport_->connected())
    return Outcome::failed(FaultCode::device_lost, "not connected: unplugged, or being opened again", "usb");
  consecutive_missed_ = 0;  // out of FAULT: the next exchanges say whether it is back
  // Homing was lost (the fault said so, and is_homed went false; or the Falcon was unplugged):
  // the counts may be relative again, so home again — on every enable until a homing is done
  // (one cut short by a fault does not count).
  if (homing_lost_ && !homing()) start_homing();
  return Outcome::done();
}

Outcome FalconDevice::home() {
  if (!homed_seen_) return Outcome::pending();
  homed_seen_ = false;
  homed_ = true;
  homing_lost_ = false;
  return Outcome::done();
}

MotorCommand FalconDevice::command(const Setpoint& s) noexcept {
  // The homing bit in every packet, homed or not: the firmware stays homed only while it is set
  // and reports homed arms only then (libnifalcon's FalconFirmware.h).
  MotorCommand c{{}, control::homing};
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  const OperatingState& st = operating_state();
  if (homing()) {
    c.dac = {config_.homing_dac, config_.homing_dac, config_.homing_dac};
  } else if (s.mode == ServoMode::cf && homed_ && measured_) {
    f = Eigen::Vector3d(s.wrench.force[0], s.wrench.force[1], s.wrench.force[2]);
    const Eigen::Vector3d p = position();
    for (int k = 0; k < 3; ++k) {  // outside the workspace: nothing pushing further out
      if (p[k] < contract().workspace_min[static_cast<std::size_t>(k)] && f[k] < 0) f[k] = 0;
      if (p[k] > contract().workspace_max[static_cast<std::size_t>(k)] && f[k] > 0) f[k] = 0;
    }
    if (kinematics_.dac(j_, f, c.dac) < 1.0) ++summary_.saturated;
  }
  leds_ = leds_of(st.state, homing(), homed_);
  c.control = static_cast<std::uint8_t>(c.control | leds_);
  servo_force_ = to_vec3(f);
  return c;
}

Outcome FalconDevice::missed(FaultCode code, const char* why, std::int32_t error) noexcept {
  if (++consecutive_missed_ <= config_.max_missed) return Outcome::done();
  return Outcome::failed(code, why, "usb", static_cast<std::uint32_t>(error < 0 ? -error : error));
}

Outcome FalconDevice::measure(const DeviceReport& r) noexcept {
  const Eigen::Vector3d theta = kinematics_.angles(r.encoder);
  const bool all_homed = r.homed(0) && r.homed(1) && r.homed(2);
  if (homing() && all_homed) {
    homed_seen_ = true;  // home() says so; the counts are absolute from now on:
    measured_ = false;   // start the velocity afresh
  } else if (homed_ && !all_homed) {
    // The firmware no longer says every arm is homed (while the bit is held): its counts may
    // have restarted from wherever the arms are, and a force from them would push blindly.
    homed_ = false;
    homing_lost_ = true;
    measured_ = false;
    lose_homing();
    return Outcome::failed(FaultCode::device_error,
                           "homing lost: the Falcon no longer reports its arms homed", "homing", r.status);
  }
  Eigen::Vector3d x;
  Eigen::Matrix3d j;
  const bool in_model = kinematics_.forward(theta, x, x_) && kinematics_.jacobian(theta, x, j);
  if (!in_model) {
    // Before homing the counts are relative: a pose out of the model means nothing yet.
    if (!homed_) return Outcome::done();
    ++summary_.out_of_model;
    return missed(FaultCode::limit_exceeded, "poses out of the model, exchange after exchange", 0);
  }
  consecutive_missed_ = 0;
  // Over the interval since the last report measured, not one period: after missed exchanges
  // (or a slower I/O thread) the arms moved for several periods.
  const TimeNs t = now();
  const double dt = static_cast<double>(t - last_report_) * 1e-9;
  if (measured_ && dt > 0)
    theta_dot_ = config_.velocity_filter * (theta - theta_) / dt + (1 - config_.velocity_filter) * theta_dot_;
  else
    theta_dot_.setZero();
  last_report_ = t;
  theta_ = theta;
  x_ = x;
  j_ = j;
  measured_ = true;
  const std::uint8_t b = r.buttons();
  button(Button::clutch, (b & config_.clutch_buttons) != 0);
  button(Button::operator_present, (b & config_.operator_buttons) != 0);
  return Outcome::done();
}

void FalconDevice::publish() noexcept {
  Measured& m = measured();
  m.cp.position = to_vec3(position());
  m.cv.linear = to_vec3(j_ * theta_dot_);
  for (std::size_t i = 0; i < 3; ++i) {
    m.js.position[i] = theta_[static_cast<Eigen::Index>(i)];
    m.js.velocity[i] = theta_dot_[static_cast<Eigen::Index>(i)];
  }
}

Outcome FalconDevice::write(const Setpoint& s) {
  const Packet out = encode_command(command(s));
  Packet in{};
  const ExchangeResult x = transport_->exchange(out, in);
  ++summary_.exchanges;
  summary_.reopened = transport_->reopened();
  Outcome o;
  switch (x.status) {
    case ExchangeStatus::ok: {
      DeviceReport r{};
      if (decode_report(std::span<const std::uint8_t>(in.data(), x.bytes), r) == FrameError::none) {
        o = measure(r);
      } else {
        ++summary_.bad_frames;  // refused, never used: the last good measurement stands
        o = missed(FaultCode::device_error, "corrupt reports, exchange after exchange", 0);
      }
      break;
    }
    case ExchangeStatus::no_answer:
      ++summary_.no_answer;
      o = missed(FaultCode::device_lost, "no answer, exchange after exchange", 0);
      break;
    case ExchangeStatus::usb_error:
      ++summary_.usb_errors;
      summary_.last_usb_error = x.error;
      o = missed(FaultCode::device_error, "USB errors, exchange after exchange", x.error);
      break;
    case ExchangeStatus::disconnected:
      summary_.last_usb_error = x.error;
      // A Falcon plugged in again (the transport's reconnect) has a fresh firmware, not homed:
      // the next enable homes it before any force.
      if (homed_) lose_homing();
      homed_ = false;
      homing_lost_ = true;
      measured_ = false;
      o = Outcome::failed(FaultCode::device_lost, "the device is gone (unplugged)", "usb",
                          static_cast<std::uint32_t>(x.error < 0 ? -x.error : x.error));
      break;
  }
  publish();
  return o;
}

}  // namespace saw::drivers::falcon
