// CanopenArm's cycle and command checks: RT code, no allocation, lock, block, stdio or throw.
#include <algorithm>
#include <cmath>

#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/log.hpp"

namespace saw::canopen {

const char* to_string(FaultReason r) noexcept {
  switch (r) {
    case FaultReason::none:
      return "none";
    case FaultReason::drive_fault:
      return "drive fault";
    case FaultReason::emcy:
      return "emergency message";
    case FaultReason::heartbeat_lost:
      return "heartbeat lost";
    case FaultReason::node_rebooted:
      return "node rebooted";
    case FaultReason::bus_off:
      return "bus off";
    case FaultReason::feedback_stale:
      return "feedback stale";
    case FaultReason::command_stale:
      return "command stale";
    case FaultReason::joint_limit:
      return "joint limit";
    case FaultReason::following_error:
      return "following error";
    case FaultReason::enable_timeout:
      return "enable timed out";
  }
  return "unknown";
}

// ---- commands ---------------------------------------------------------------------------

void CanopenArm::refuse(std::uint64_t& counter) noexcept {
  ++counter;
  // Never the refused value, nor the last good one for ever: hold where the drive is told to be.
  for (std::size_t i = 0; i < n_; ++i) command_[i] = config_.mode == cia402::csp ? target_[i] : 0.0;
}

void CanopenArm::servo_joints(const JointState& js, cia402::Mode mode) noexcept {
  const TimeNs t = now();
  last_command_ = t;
  commanded_ = true;
  command_timeout_ = false;
  if (mode != config_.mode) return refuse(refused_.wrong_mode);
  if (js.size != n_) return refuse(refused_.wrong_size);
  const auto& values = mode == cia402::csp ? js.position : mode == cia402::csv ? js.velocity : js.effort;
  // servo_jp may move no faster than max_velocity since the last accepted command (bounded by
  // the command timeout, so that a command after a pause cannot jump).
  const double since =
      static_cast<double>(std::clamp(t - last_accepted_, config().period.count(), config_.command_timeout)) *
      1e-9;
  for (std::size_t i = 0; i < n_; ++i) {
    const double v = values[i];
    const JointConfig& j = config_.joints[i];
    if (!std::isfinite(v)) return refuse(refused_.not_finite);
    const bool over = mode == cia402::csp
                          ? (v < j.min || v > j.max || std::abs(v - target_[i]) > j.max_velocity * since)
                      : mode == cia402::csv ? std::abs(v) > j.max_velocity
                                            : std::abs(v) > max_torque_[i];
    if (over) return refuse(refused_.over_limit);
  }
  for (std::size_t i = 0; i < n_; ++i) command_[i] = values[i];
  last_accepted_ = t;
}

void CanopenArm::servo_cf(const Wrench& w) noexcept {
  last_command_ = now();
  commanded_ = true;
  command_timeout_ = false;
  if (config_.mode != cia402::cst) return refuse(refused_.wrong_mode);
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(w.force[k]) || !std::isfinite(w.torque[k])) return refuse(refused_.not_finite);
  const double f = std::hypot(w.force[0], w.force[1], w.force[2]);
  if (config_.max_force > 0 && f > config_.max_force) return refuse(refused_.over_limit);
  Joints tau{};
  kinematics_->joint_torques(std::span(q_.data(), n_), w, std::span(tau.data(), n_));
  for (std::size_t i = 0; i < n_; ++i) {
    if (!std::isfinite(tau[i])) return refuse(refused_.not_finite);
    if (std::abs(tau[i]) > max_torque_[i]) return refuse(refused_.over_limit);
  }
  for (std::size_t i = 0; i < n_; ++i) command_[i] = tau[i];
  last_accepted_ = now();
}

// ---- the cycle ----------------------------------------------------------------------------

void CanopenArm::run() {
  const TimeNs t = now();
  if (start_time_ < 0) start_time_ = t;
  master_->receive(t);
  read_feedback();
  if (enable_requested_) {
    enable_requested_ = false;
    if (!(state_.state == OperatingStateValue::enabled && !enabling_)) {
      if (fault_.code != FaultCode::none) {
        fault_ = {};
        reason_ = FaultReason::none;
        (void)(*fault_event_)(fault_);
      }
      for (std::size_t i = 0; i < n_; ++i) master_->request_fault_reset(i, t);
      target_all(cia402::Target::operation_enabled);
      enabling_ = true;
      commanded_ = command_timeout_ = false;
      state_.is_busy = true;  // DISABLED and busy until every drive is in operation enabled
      state_.state = OperatingStateValue::disabled;
      (void)(*state_event_)(state_);
    }
  }
  check_health();
  step_state();
  watch_commands();
  send_setpoints();
  master_->transmit(t);
  publish();
}

void CanopenArm::read_feedback() noexcept {
  for (std::size_t i = 0; i < n_; ++i) {
    const AxisFeedback& f = master_->feedback(i);
    q_[i] = f.position + config_.joints[i].offset;
    qd_[i] = f.velocity;
    tau_[i] = f.torque;
    measured_js_.position[i] = q_[i];
    measured_js_.velocity[i] = f.velocity;
    measured_js_.effort[i] = f.torque;
  }
  if (kinematics_) {
    measured_cp_ = kinematics_->fk(std::span(q_.data(), n_));
    measured_cv_ = kinematics_->velocity(std::span(q_.data(), n_), std::span(qd_.data(), n_));
  }
}

void CanopenArm::raise_fault(FaultReason reason, FaultCode code, std::size_t axis, std::uint32_t detail,
                             TimeNs age) noexcept {
  if (state_.state == OperatingStateValue::fault) return;
  const TimeNs t = now();
  fault_ = {};
  fault_.code = code;
  fault_.detail = detail;
  fault_.age_ns = age;
  fault_.time = t;
  fault_.since_start_ns = t - start_time_;
  fault_.set_source(axis < n_ ? std::string_view(config_.joints[axis].name) : std::string_view("bus"));
  reason_ = reason;
  ++faults_;
  enabling_ = false;
  state_.is_busy = false;
  target_all(cia402::Target::quick_stop);
  saw::log(LogLevel::error, name().c_str(), "FAULT: {} ({}) on {}, node {}, detail {}", to_string(reason),
           saw::to_string(code).data(), axis < n_ ? config_.joints[axis].name.c_str() : "the bus",
           axis < n_ ? unsigned{config_.joints[axis].node} : 0u, detail);
  (void)(*fault_event_)(fault_);
  set_state(OperatingStateValue::fault);
}

void CanopenArm::check_axis(std::size_t i) noexcept {
  const AxisHealth& h = master_->health(i);
  const AxisFeedback& f = master_->feedback(i);
  const JointConfig& j = config_.joints[i];
  const TimeNs t = now();
  if (h.boot_ups != boot_ups_seen_[i]) {
    boot_ups_seen_[i] = h.boot_ups;
    rebooted_[i] = true;  // its PDOs and mode are gone: only a new start-up brings them back
  }
  if (h.emcy_count != emcy_seen_[i]) {
    emcy_seen_[i] = h.emcy_count;
    saw::log(LogLevel::error, name().c_str(), "{}: EMCY {} ({})", j.name.c_str(), unsigned{h.last_emcy},
             emcy_name(h.last_emcy).data());
    return raise_fault(FaultReason::emcy, FaultCode::device_error, i, h.last_emcy);
  }
  if (rebooted_[i]) return raise_fault(FaultReason::node_rebooted, FaultCode::device_lost, i);
  if (h.heartbeat_lost) {
    // A drive that went silent altogether faults first for its TPDOs (they come every cycle);
    // once its heartbeat is overdue too, the fault says what is known now: the node is gone.
    if (state_.state == OperatingStateValue::fault && reason_ == FaultReason::feedback_stale &&
        fault_.source_name() == j.name) {
      reason_ = FaultReason::heartbeat_lost;
      fault_.code = FaultCode::device_lost;
      fault_.age_ns = h.silent_for;
      saw::log(LogLevel::error, name().c_str(), "FAULT: {}: heartbeat lost too, silent for {} ns",
               j.name.c_str(), h.silent_for);
      (void)(*fault_event_)(fault_);
      return;
    }
    return raise_fault(FaultReason::heartbeat_lost, FaultCode::device_lost, i, 0, h.silent_for);
  }
  const TimeNs age = t - (f.valid ? f.last_received : start_time_);
  if (age > config_.feedback_timeout)
    return raise_fault(FaultReason::feedback_stale, FaultCode::input_stale, i, 0, age);
  // A drive in fault while no reset is under way (an enable resets it, and has its own timeout).
  const bool drive_fault = f.state == cia402::State::fault || f.state == cia402::State::fault_reaction_active;
  if (drive_fault && !enabling_)
    return raise_fault(FaultReason::drive_fault, FaultCode::device_error, i, h.last_emcy);
  if (master_->control(i).progress == cia402::Progress::timeout && enabling_)
    return raise_fault(FaultReason::enable_timeout, FaultCode::device_error, i, f.statusword);
  const bool powered = enabling_ || state_.state == OperatingStateValue::enabled ||
                       state_.state == OperatingStateValue::paused;
  if (!powered || !f.valid) return;
  if (q_[i] < j.min || q_[i] > j.max)
    return raise_fault(FaultReason::joint_limit, FaultCode::limit_exceeded, i);
  // The position read now answers the target sent one SYNC before.
  if (config_.mode == cia402::csp && j.following_error > 0 && following() &&
      std::abs(master_->setpoint(i) + j.offset - q_[i]) > j.following_error)
    return raise_fault(FaultReason::following_error, FaultCode::limit_exceeded, i);
}

void CanopenArm::check_health() noexcept {
  const can::BusState bus = bus_.state();
  status_.bus_state = static_cast<std::uint8_t>(bus);
  if (bus == can::BusState::bus_off || bus == can::BusState::down)
    raise_fault(FaultReason::bus_off, FaultCode::device_lost, n_, static_cast<std::uint32_t>(bus));
  for (std::size_t i = 0; i < n_; ++i) check_axis(i);
}

void CanopenArm::step_state() noexcept {
  if (!enabling_) return;
  for (std::size_t i = 0; i < n_; ++i)
    if (master_->feedback(i).state != cia402::State::operation_enabled) return;
  enabling_ = false;
  state_.is_busy = false;
  // Start from where the drives are: no jump at the first cycle enabled.
  for (std::size_t i = 0; i < n_; ++i) command_[i] = config_.mode == cia402::csp ? q_[i] : 0.0;
  state_.state = OperatingStateValue::enabled;
  (void)(*state_event_)(state_);
}

void CanopenArm::watch_commands() noexcept {
  if (!commanded_ || !following() || now() - last_command_ <= config_.command_timeout) return;
  commanded_ = false;
  command_timeout_ = true;
  ++watchdog_trips_;
  for (std::size_t i = 0; i < n_; ++i) command_[i] = config_.mode == cia402::csp ? target_[i] : 0.0;
  saw::log(LogLevel::warning, name().c_str(), "no servo command for {} ns: holding (zero velocity or torque)",
           now() - last_command_);
  if (config_.on_command_timeout == CommandTimeoutAction::fault)
    raise_fault(FaultReason::command_stale, FaultCode::input_stale, n_, 0, now() - last_command_);
}

void CanopenArm::send_setpoints() noexcept {
  const bool drive = following() && commanded_;
  for (std::size_t i = 0; i < n_; ++i) {
    double sp = 0;
    if (config_.mode == cia402::csp) {
      // Not following: the target tracks the drive, so that enabling never jumps; following
      // without a fresh command: the last target is held.
      sp = !following() ? q_[i] : drive ? command_[i] : target_[i];
    } else {
      sp = drive ? command_[i] : 0.0;
    }
    const double drive_sp = config_.mode == cia402::csp ? sp - config_.joints[i].offset : sp;
    if (master_->set_setpoint(i, drive_sp) == Codec::ok) target_[i] = sp;
    setpoint_js_.position[i] = config_.mode == cia402::csp ? target_[i] : q_[i];
    setpoint_js_.velocity[i] = config_.mode == cia402::csv ? target_[i] : 0.0;
    setpoint_js_.effort[i] = config_.mode == cia402::cst ? target_[i] : 0.0;
  }
}

void CanopenArm::publish() noexcept {
  const MasterCounters& c = master_->counters();
  const can::BusCounters bus = bus_.counters();
  status_.state = state_.state;
  status_.reason = reason_;
  status_.faults = faults_;
  if (fault_.code != FaultCode::none) status_.fault = fault_;
  status_.frames_received = c.frames_received;
  status_.frames_sent = c.frames_sent;
  status_.send_refused = c.send_refused;
  status_.foreign_frames = c.foreign_frames;
  status_.syncs = c.syncs;
  status_.emcy = c.emcy;
  status_.sdo_done = c.sdo_done;
  status_.sdo_failed = c.sdo_failed;
  status_.sdo_refused = master_->sdo_queue().refused();
  std::uint64_t losses = 0, bad = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    losses += master_->health(i).heartbeat_losses;
    bad += master_->health(i).bad_pdos;
  }
  status_.heartbeat_losses = losses;
  status_.bad_pdos = bad + bus.malformed;
  status_.watchdog_trips = watchdog_trips_;
  status_.refused = refused_;
}

}  // namespace saw::canopen
