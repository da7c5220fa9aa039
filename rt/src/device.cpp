// Device's set-up, start and stop, and its commands' checks (run in the device's thread).
#include "saw/device.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "saw/log.hpp"

namespace saw {

std::string_view to_string(SafeState s) noexcept {
  switch (s) {
    case SafeState::zero_force:
      return "zero force";
    case SafeState::hold:
      return "hold";
    case SafeState::drive_disabled:
      return "drive disabled";
  }
  return "?";
}

const char* to_string(SafeReason r) noexcept {
  switch (r) {
    case SafeReason::disable:
      return "disable";
    case SafeReason::fault:
      return "fault";
    case SafeReason::stop:
      return "stop";
    case SafeReason::start_failed:
      return "failed start";
  }
  return "?";
}

const char* to_string(ServoMode m) noexcept {
  switch (m) {
    case ServoMode::none:
      return "none";
    case ServoMode::cf:
      return "servo_cf";
    case ServoMode::jp:
      return "servo_jp";
    case ServoMode::jv:
      return "servo_jv";
    case ServoMode::jf:
      return "servo_jf";
    case ServoMode::cp:
      return "servo_cp";
  }
  return "?";
}

std::string_view DeviceStatus::reason_text() const noexcept {
  std::size_t n = 0;
  while (n < max_reason && reason[n] != '\0') ++n;
  return {reason.data(), n};
}

namespace {

DeviceConfig checked(DeviceConfig c, const TaskConfig& task, const std::string& name) {
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument("device '" + name + "': " + what);
  };
  if (!task.is_periodic()) fail("must be periodic");
  if (c.joints.size() > JointState::max_joints) fail("at most 8 joints");
  if ((c.servo_jp || c.servo_jv || c.servo_jf) && c.joints.empty()) fail("joint commands need joints");
  if (c.servo_cf && !c.cartesian) fail("servo_cf needs a Cartesian device");
  if (c.servo_cp && !c.cartesian) fail("servo_cp needs a Cartesian device");
  if (!(c.max_linear_speed > 0) || !(c.max_angular_speed > 0)) fail("servo_cp speeds must be positive");
  for (std::size_t k = 0; k < 3; ++k)
    if (!(c.workspace_min[k] <= c.workspace_max[k])) fail("the workspace's min is above its max");
  if (!(c.max_force >= 0)) fail("max_force must not be negative");
  if (c.command_timeout == 0) c.command_timeout = 3 * task.period.count();
  if (c.command_timeout < task.period.count()) fail("command_timeout must be at least one period");
  if (c.enable_timeout <= 0) fail("enable_timeout must be positive");
  for (const auto& j : c.joints) {
    if (j.name.size() > JointState::max_name) fail("joint name '" + j.name + "' is too long");
    if (!(j.min <= j.max)) fail("joint '" + j.name + "': min above max");
    if (!(j.max_velocity > 0) || !(j.max_effort > 0)) fail("joint '" + j.name + "': limits must be positive");
  }
  return c;
}

}  // namespace

Device::Device(std::string name, TaskConfig task, DeviceConfig config)
    : Task(std::move(name), task),
      config_(checked(std::move(config), task, this->name())),
      watchdog_(state_table()) {
  watchdog_.set_timeout(config_.command_timeout);
  measured_.js.size = static_cast<std::uint32_t>(config_.joints.size());
  for (std::size_t i = 0; i < config_.joints.size(); ++i)
    (void)measured_.js.set_name(i, config_.joints[i].name);
  status_.safe_state = config_.safe_state;
  status_.command_timeout = config_.command_timeout;
  provide_interfaces();
}

Device::~Device() = default;

void Device::provide_interfaces() {
  namespace arm_if = crtk::arm;
  auto& st = state_table();
  arm_ = &provide(config_.interface_name);
  auto& a = *arm_;
  if (config_.cartesian) {
    columns_.measured_cp = crtk::provide(a, arm_if::measured_cp, st, &measured_.cp);
    columns_.measured_cv = crtk::provide(a, arm_if::measured_cv, st, &measured_.cv);
  }
  if (!config_.joints.empty())
    columns_.measured_js = crtk::provide(a, arm_if::measured_js, st, &measured_.js);
  columns_.operating_state = crtk::provide(a, arm_if::operating_state, st, &state_);
  columns_.fault = st.add_column("fault", &fault_);
  a.add_command_read("fault", columns_.fault);
  a.add_command_read("command_timeout", watchdog_.holding_column());
  a.add_command_read("watchdog_trips", watchdog_.trips_column());
  columns_.status = st.add_column("device", &status_, ColumnUse::summary);
  if (config_.servo_cf) {
    crtk::provide(a, arm_if::servo_cf, [this](const Wrench& w) { servo_cf(w); });
    // Declared for callers outside the host (the gateway checks it); servo_cf() checks the norm.
    if (config_.max_force > 0) a.limit(arm_if::servo_cf.name, -config_.max_force, config_.max_force);
  }
  if (config_.servo_cp) crtk::provide(a, arm_if::servo_cp, [this](const Pose& p) { servo_cp(p); });
  if (config_.servo_jp)
    crtk::provide(a, arm_if::servo_jp, [this](const JointState& js) { servo_joints(js, ServoMode::jp); });
  if (config_.servo_jv)
    crtk::provide(a, arm_if::servo_jv, [this](const JointState& js) { servo_joints(js, ServoMode::jv); });
  if (config_.servo_jf)
    crtk::provide(a, arm_if::servo_jf, [this](const JointState& js) { servo_joints(js, ServoMode::jf); });
  crtk::provide(a, arm_if::state_command, [this](const StateCommand& c) { state_command(c); });
  state_event_ = &crtk::provide(a, arm_if::operating_state_event);
  fault_event_ = &a.add_event_write<FaultInfo>("fault");
  clutch_event_ = &crtk::provide(a, arm_if::clutch);
  operator_event_ = &crtk::provide(a, arm_if::operator_present);
}

// ---- start and stop (not RT) ------------------------------------------------------------

void Device::startup() {
  try {
    open();
  } catch (...) {
    // Whatever the hardware got so far, it is left safe and released before the start fails.
    safe(SafeReason::start_failed);
    close();
    throw;
  }
  if (config_.start_enabled) enable_requested_ = true;
}

void Device::cleanup() {
  enabling_ = homing_ = enable_requested_ = false;
  command_ = {};
  watchdog_.disarm();
  safe(SafeReason::stop);
  // The last thing the hardware is sent is the safe output.
  (void)guarded([&] { return write(Setpoint{}); });
  status_.safe_output = true;
  close();
}

// ---- commands: checked here, so that the driver never sees a bad one ----------------------

void Device::refuse(std::uint64_t& counter) noexcept {
  ++counter;
  command_ = {};  // never the refused value, nor the last good one for ever: the safe output
}

void Device::end_servo() noexcept {
  command_ = {};
  watchdog_.disarm();
  has_jp_ = has_cp_ = false;  // the hardware moves on its own: the next step is judged from where it is
}

void Device::servo_cf(const Wrench& w) noexcept {
  watchdog_.commanded(now());  // a refused command is fresh too: it takes the safe output itself
  if (!accepts(ServoMode::cf)) return refuse(status_.refused.wrong_mode);
  for (std::size_t k = 0; k < 3; ++k)
    if (!std::isfinite(w.force[k]) || !std::isfinite(w.torque[k])) return refuse(status_.refused.not_finite);
  if (config_.max_force > 0 && std::hypot(w.force[0], w.force[1], w.force[2]) > config_.max_force)
    return refuse(status_.refused.over_limit);
  Setpoint s;
  s.mode = ServoMode::cf;
  s.wrench = w;
  if (!admit(s)) return refuse(status_.refused.over_limit);
  command_ = s;
}

void Device::servo_joints(const JointState& js, ServoMode mode) noexcept {
  const TimeNs t = now();
  watchdog_.commanded(t);
  if (!accepts(mode)) return refuse(status_.refused.wrong_mode);
  const std::size_t n = config_.joints.size();
  if (js.size != n) return refuse(status_.refused.wrong_size);
  const auto& values = mode == ServoMode::jp ? js.position : mode == ServoMode::jv ? js.velocity : js.effort;
  // servo_jp may move no faster than max_velocity from the last accepted position (or, first,
  // from where the joints are), over the time since (bounded by the command timeout, so that a
  // command after a pause cannot jump).
  const double since =
      static_cast<double>(std::clamp(t - last_jp_time_, config().period.count(), config_.command_timeout)) *
      1e-9;
  Setpoint s;
  s.mode = mode;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = values[i];
    const JointLimits& j = config_.joints[i];
    if (!std::isfinite(v)) return refuse(status_.refused.not_finite);
    bool over = false;
    if (mode == ServoMode::jp) {
      const double from = has_jp_ ? last_jp_[i] : measured_.js.position[i];
      over = v < j.min || v > j.max || std::abs(v - from) > j.max_velocity * since;
    } else {
      over = std::abs(v) > (mode == ServoMode::jv ? j.max_velocity : j.max_effort);
    }
    if (over) return refuse(status_.refused.over_limit);
    s.joints[i] = v;
  }
  if (!admit(s)) return refuse(status_.refused.over_limit);
  command_ = s;
  if (mode == ServoMode::jp) {
    last_jp_ = s.joints;
    last_jp_time_ = t;
    has_jp_ = true;
  }
}

void Device::servo_cp(const Pose& p) noexcept {
  const TimeNs t = now();
  watchdog_.commanded(t);
  if (!accepts(ServoMode::cp)) return refuse(status_.refused.wrong_mode);
  for (std::size_t k = 0; k < 3; ++k)
    if (!std::isfinite(p.position[k])) return refuse(status_.refused.not_finite);
  for (std::size_t k = 0; k < 4; ++k)
    if (!std::isfinite(p.orientation[k])) return refuse(status_.refused.not_finite);
  // A quaternion off the unit sphere is no rotation: refused as out of range, never normalised.
  if (!Pose::valid(p)) return refuse(status_.refused.over_limit);
  for (std::size_t k = 0; k < 3; ++k)
    if (p.position[k] < config_.workspace_min[k] || p.position[k] > config_.workspace_max[k])
      return refuse(status_.refused.over_limit);
  // As servo_jp's step: from the last accepted pose (or, first, the measured one), over the time
  // since (bounded by the command timeout: a command after a pause cannot jump).
  const double since =
      static_cast<double>(std::clamp(t - last_cp_time_, config().period.count(), config_.command_timeout)) *
      1e-9;
  const Pose& from = has_cp_ ? last_cp_ : measured_.cp;
  const double dx = p.position[0] - from.position[0], dy = p.position[1] - from.position[1],
               dz = p.position[2] - from.position[2];
  if (std::sqrt(dx * dx + dy * dy + dz * dz) > config_.max_linear_speed * since)
    return refuse(status_.refused.over_limit);
  double dot = 0;
  for (std::size_t k = 0; k < 4; ++k) dot += p.orientation[k] * from.orientation[k];
  const double angle = 2 * std::acos(std::min(1.0, std::abs(dot)));  // q and -q: one rotation
  if (angle > config_.max_angular_speed * since) return refuse(status_.refused.over_limit);
  Setpoint s;
  s.mode = ServoMode::cp;
  s.pose = p;
  if (!admit(s)) return refuse(status_.refused.over_limit);
  command_ = s;
  last_cp_ = p;
  last_cp_time_ = t;
  has_cp_ = true;
}

void Device::state_command(StateCommand c) noexcept {
  switch (c) {
    case StateCommand::enable:
      enable_requested_ = true;  // acted on in the cycle, with its measurements
      break;
    case StateCommand::disable:
      enable_requested_ = enabling_ = false;
      command_ = {};
      watchdog_.disarm();
      safe(SafeReason::disable);
      moving_ = false;
      state_.is_busy = busy();
      if (state_.state != OperatingStateValue::disabled) set_state(OperatingStateValue::disabled);
      break;
    case StateCommand::pause:
      if (state_.state == OperatingStateValue::enabled && !enabling_) set_state(OperatingStateValue::paused);
      break;
    case StateCommand::resume:
      if (state_.state == OperatingStateValue::paused) set_state(OperatingStateValue::enabled);
      break;
    case StateCommand::home:
      if (state_.state == OperatingStateValue::fault) break;
      start_homing();
      (void)(*state_event_)(state_);
      break;
  }
}

}  // namespace saw
