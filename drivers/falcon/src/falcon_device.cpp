#include "saw/drivers/falcon/falcon_device.hpp"

#include <cmath>
#include <span>
#include <stdexcept>

#include "saw/eigen.hpp"
#include "saw/log.hpp"

namespace saw::drivers::falcon {
namespace {

FalconConfig checked(FalconConfig c, const TaskConfig& task) {
  if (c.command_timeout == 0) c.command_timeout = 3 * task.period.count();
  if (c.command_timeout < task.period.count())
    throw std::invalid_argument("command_timeout must be at least one period");
  if (!(c.max_force > 0)) throw std::invalid_argument("max_force must be positive");
  if ((c.workspace_min.array() >= c.workspace_max.array()).any())
    throw std::invalid_argument("workspace_min must be below workspace_max");
  if (c.max_missed < 1) throw std::invalid_argument("max_missed must be at least 1");
  if (!(c.velocity_filter > 0 && c.velocity_filter <= 1))
    throw std::invalid_argument("velocity_filter in (0, 1]");
  return c;
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
    : Task(std::move(name), task),
      config_(checked(std::move(config), task)),
      kinematics_(config_.geometry),
      transport_(std::move(transport)) {
  if (!task.is_periodic())
    throw std::invalid_argument("FalconDevice '" + this->name() + "' must be periodic");
  if (!transport_) throw std::invalid_argument("FalconDevice '" + this->name() + "': no transport");
  origin_ = config_.origin;
  if (!origin_.allFinite() && !kinematics_.forward(kinematics_.angles({0, 0, 0}), origin_))
    throw std::invalid_argument("FalconDevice: the geometry has no pose at encoder counts 0");
  x_ = origin_;
  measured_js_.size = 3;
  for (std::size_t i = 0; i < 3; ++i)
    (void)measured_js_.set_name(i, i == 0 ? "arm0" : i == 1 ? "arm1" : "arm2");
  state_.state = OperatingStateValue::disabled;
  summary_.command_timeout = config_.command_timeout;
  publish();

  auto& st = state_table();
  namespace arm_if = crtk::arm;
  auto& arm = provide(std::string(arm_if::interface_name));
  crtk::provide(arm, arm_if::measured_cp, st, &measured_cp_);
  crtk::provide(arm, arm_if::measured_cv, st, &measured_cv_);
  crtk::provide(arm, arm_if::measured_js, st, &measured_js_);
  crtk::provide(arm, arm_if::operating_state, st, &state_);
  arm.add_command_read("servo_force", st.add_column("servo_force", &servo_force_));
  watchdog_.set_timeout(config_.command_timeout);
  arm.add_command_read("command_timeout", watchdog_.holding_column());
  arm.add_command_read("watchdog_trips", watchdog_.trips_column());
  arm.add_command_read("fault", st.add_column("fault", &fault_));
  crtk::provide(arm, arm_if::servo_cf, [this](const Wrench& w) { servo_cf(w); });
  arm.limit(arm_if::servo_cf.name, -config_.max_force, config_.max_force);
  crtk::provide(arm, arm_if::state_command, [this](const StateCommand& c) { state_command(c); });
  state_event_ = &crtk::provide(arm, arm_if::operating_state_event);
  clutch_event_ = &crtk::provide(arm, arm_if::clutch);
  operator_event_ = &crtk::provide(arm, arm_if::operator_present);
  fault_event_ = &arm.add_event_write<FaultInfo>("fault");
  auto& falcon = provide("falcon");
  falcon.add_command_read("summary", st.add_column("summary", &summary_, ColumnUse::summary));
  falcon.add_command_read("leds", st.add_column("leds", &leds_));
}

FalconDevice::~FalconDevice() = default;

void FalconDevice::startup() {
  transport_->open();  // throws TransportError saying what is wrong: the deployment stops here
  homing_ = config_.home_on_start;
  homing_start_ = -1;
  // Busy while homing, as after a `home` command: a teleoperation holds until the positions are
  // absolute (before, they count from wherever the arms were at power-up).
  state_.is_busy = homing_;
  if (config_.start_enabled) state_.state = OperatingStateValue::enabled;
}

void FalconDevice::cleanup() {
  // Leave the motors unpowered: one zero command, then let the device go.
  Packet in{};
  (void)transport_->exchange(encode_command(MotorCommand{}), in);
  transport_->close();
}

void FalconDevice::servo_cf(const Wrench& w) noexcept {
  watchdog_.commanded(now());  // a refused command is fresh too: it zeroes the force itself
  const Eigen::Vector3d f(w.force[0], w.force[1], w.force[2]);
  if (!f.allFinite() || f.norm() > config_.max_force) {
    force_.setZero();  // never to the motors, nor keep pushing with the last good one
    ++summary_.refused_commands;
    return;
  }
  force_ = f;
}

void FalconDevice::watch_commands() noexcept {
  if (!watchdog_.expired(now())) return;
  force_.setZero();
  saw::log(LogLevel::warning, name().c_str(), "no servo_cf for {} ns: force dropped to zero",
           now() - watchdog_.last_command());
}

void FalconDevice::set_state(OperatingStateValue s) noexcept {
  if (state_.state == s) return;
  state_.state = s;
  (void)(*state_event_)(state_);
}

void FalconDevice::state_command(StateCommand c) noexcept {
  switch (c) {
    case StateCommand::enable:
      consecutive_missed_ = 0;  // out of FAULT: the next exchanges say whether it is back
      set_state(OperatingStateValue::enabled);
      break;
    case StateCommand::disable:
      set_state(OperatingStateValue::disabled);
      break;
    case StateCommand::pause:
      if (state_.state == OperatingStateValue::enabled) set_state(OperatingStateValue::paused);
      break;
    case StateCommand::resume:
      if (state_.state == OperatingStateValue::paused) set_state(OperatingStateValue::enabled);
      break;
    case StateCommand::home:
      if (state_.state == OperatingStateValue::fault) break;
      homing_ = true;
      homing_start_ = -1;
      state_.is_busy = true;
      (void)(*state_event_)(state_);
      break;
  }
}

MotorCommand FalconDevice::command() noexcept {
  MotorCommand c{};
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  const bool fault = state_.state == OperatingStateValue::fault;
  if (homing_ && !fault) {
    c.dac = {config_.homing_dac, config_.homing_dac, config_.homing_dac};
    c.control = control::homing;
  } else if (state_.state == OperatingStateValue::enabled && state_.is_homed && measured_) {
    f = force_;
    const Eigen::Vector3d p = position();
    for (int k = 0; k < 3; ++k) {  // outside the workspace: nothing pushing further out
      if (p[k] < config_.workspace_min[k] && f[k] < 0) f[k] = 0;
      if (p[k] > config_.workspace_max[k] && f[k] > 0) f[k] = 0;
    }
    if (kinematics_.dac(j_, f, c.dac) < 1.0) ++summary_.saturated;
  }
  leds_ = leds_of(state_.state, homing_, state_.is_homed);
  c.control = static_cast<std::uint8_t>(c.control | leds_);
  servo_force_ = to_vec3(f);
  return c;
}

void FalconDevice::raise(FaultCode code, std::int32_t error) noexcept {
  force_.setZero();
  watchdog_.disarm();
  homing_ = false;
  state_.is_busy = false;
  if (state_.state == OperatingStateValue::fault) return;
  fault_ = {};
  fault_.code = code;
  fault_.last_read = Status::ok;
  fault_.detail = static_cast<std::uint32_t>(error < 0 ? -error : error);
  fault_.time = now();
  fault_.since_start_ns = now() - t0_;
  fault_.set_source(code == FaultCode::limit_exceeded ? "homing" : "usb");
  ++summary_.faults;
  summary_.fault = fault_;
  saw::log(LogLevel::error, name().c_str(), "FAULT, zero force: {} ({} failed exchanges in a row, error {})",
           to_string(code).data(), consecutive_missed_, error);
  (void)(*fault_event_)(fault_);
  set_state(OperatingStateValue::fault);
}

void FalconDevice::missed(FaultCode code, std::int32_t error) noexcept {
  if (++consecutive_missed_ > config_.max_missed) raise(code, error);
}

void FalconDevice::measure(const DeviceReport& r) noexcept {
  const Eigen::Vector3d theta = kinematics_.angles(r.encoder);
  if (homing_ && r.homed(0) && r.homed(1) && r.homed(2)) {
    homing_ = false;  // the counts are absolute from now on: start the velocity afresh
    measured_ = false;
    state_.is_homed = true;
    state_.is_busy = false;
    (void)(*state_event_)(state_);
  }
  Eigen::Vector3d x;
  Eigen::Matrix3d j;
  const bool in_model = kinematics_.forward(theta, x) && kinematics_.jacobian(theta, x, j);
  if (!in_model) {
    // Before homing the counts are relative: a pose out of the model means nothing yet.
    if (state_.is_homed) {
      ++summary_.out_of_model;
      missed(FaultCode::limit_exceeded, 0);
    }
    return;
  }
  consecutive_missed_ = 0;
  const double dt = static_cast<double>(config().period.count()) * 1e-9;
  if (measured_)
    theta_dot_ = config_.velocity_filter * (theta - theta_) / dt + (1 - config_.velocity_filter) * theta_dot_;
  else
    theta_dot_.setZero();
  theta_ = theta;
  x_ = x;
  j_ = j;
  measured_ = true;
  const std::uint8_t b = r.buttons();
  const bool clutch = b & config_.clutch_buttons, was_clutch = buttons_ & config_.clutch_buttons;
  const bool present = b & config_.operator_buttons, was_present = buttons_ & config_.operator_buttons;
  if (clutch != was_clutch) (void)(*clutch_event_)(ButtonEvent{clutch});
  if (present != was_present) (void)(*operator_event_)(ButtonEvent{present});
  buttons_ = b;
}

void FalconDevice::publish() noexcept {
  measured_cp_.position = to_vec3(position());
  measured_cv_.linear = to_vec3(j_ * theta_dot_);
  for (std::size_t i = 0; i < 3; ++i) {
    measured_js_.position[i] = theta_[static_cast<Eigen::Index>(i)];
    measured_js_.velocity[i] = theta_dot_[static_cast<Eigen::Index>(i)];
  }
  summary_.watchdog_trips = watchdog_.trips();
}

void FalconDevice::run() {
  if (t0_ < 0) t0_ = now();
  if (homing_ && homing_start_ < 0) homing_start_ = now();
  if (homing_ && now() - homing_start_ > config_.homing_timeout) raise(FaultCode::limit_exceeded, 0);
  watch_commands();
  const Packet out = encode_command(command());
  Packet in{};
  const ExchangeResult x = transport_->exchange(out, in);
  ++summary_.exchanges;
  switch (x.status) {
    case ExchangeStatus::ok: {
      DeviceReport r{};
      if (decode_report(std::span<const std::uint8_t>(in.data(), x.bytes), r) == FrameError::none) {
        measure(r);
      } else {
        ++summary_.bad_frames;  // refused, never used: the last good measurement stands
        missed(FaultCode::device_error, 0);
      }
      break;
    }
    case ExchangeStatus::no_answer:
      ++summary_.no_answer;
      missed(FaultCode::device_lost, 0);
      break;
    case ExchangeStatus::usb_error:
      ++summary_.usb_errors;
      summary_.last_usb_error = x.error;
      missed(FaultCode::device_error, x.error);
      break;
    case ExchangeStatus::disconnected:
      summary_.last_usb_error = x.error;
      raise(FaultCode::device_lost, x.error);
      break;
  }
  publish();
}

}  // namespace saw::drivers::falcon
