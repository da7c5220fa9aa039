// CanopenArm's cycle and command checks: RT code, no allocation, lock, block, stdio or throw.
#include <algorithm>
#include <cmath>
#include <span>

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

// ---- commands: the base has checked them; servo_cf becomes joint torques here ---------------

bool CanopenArm::admit(Setpoint& s) {
  if (s.mode != ServoMode::cf) return true;
  Joints tau{};
  kinematics_->joint_torques(std::span(q_.data(), n_), s.wrench, std::span(tau.data(), n_));
  for (std::size_t i = 0; i < n_; ++i)
    if (!std::isfinite(tau[i]) || std::abs(tau[i]) > config_.joints[i].max_torque) return false;
  s.mode = ServoMode::jf;
  s.joints = tau;
  return true;
}

// ---- the cycle ----------------------------------------------------------------------------

Outcome CanopenArm::read() {
  const TimeNs t = now();
  if (start_time_ < 0) start_time_ = t;
  master_->receive(t);
  read_feedback();
  return check_health();
}

Outcome CanopenArm::enable() {
  const TimeNs t = now();
  if (!enable_sent_) {
    reason_ = FaultReason::none;
    for (std::size_t i = 0; i < n_; ++i) master_->request_fault_reset(i, t);
    target_all(cia402::Target::operation_enabled);
    enable_sent_ = true;
    return Outcome::pending();
  }
  for (std::size_t i = 0; i < n_; ++i)
    if (master_->control(i).progress == cia402::Progress::timeout)
      return failure(FaultReason::enable_timeout, FaultCode::device_error, i,
                     master_->feedback(i).statusword);
  for (std::size_t i = 0; i < n_; ++i)
    if (master_->feedback(i).state != cia402::State::operation_enabled) return Outcome::pending();
  enable_sent_ = false;
  return Outcome::done();
}

Outcome CanopenArm::write(const Setpoint& s) {
  send_setpoints(s);
  master_->transmit(now());
  publish();
  return Outcome::done();
}

void CanopenArm::read_feedback() noexcept {
  JointState& js = measured().js;
  for (std::size_t i = 0; i < n_; ++i) {
    const AxisFeedback& f = master_->feedback(i);
    q_[i] = f.position + config_.joints[i].offset;
    qd_[i] = f.velocity;
    tau_[i] = f.torque;
    js.position[i] = q_[i];
    js.velocity[i] = f.velocity;
    js.effort[i] = f.torque;
  }
  if (kinematics_) {
    measured().cp = kinematics_->fk(std::span(q_.data(), n_));
    measured().cv = kinematics_->velocity(std::span(q_.data(), n_), std::span(qd_.data(), n_));
  }
}

Outcome CanopenArm::failure(FaultReason reason, FaultCode code, std::size_t axis, std::uint32_t detail,
                            TimeNs age) noexcept {
  // The base keeps the first cause of a fault: so does the reason.
  if (operating_state().state != OperatingStateValue::fault) reason_ = reason;
  const std::string_view source =
      axis < n_ ? std::string_view(config_.joints[axis].name) : std::string_view("bus");
  return Outcome::failed(code, to_string(reason), source, detail, age);
}

Outcome CanopenArm::check_axis(std::size_t i) noexcept {
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
    return failure(FaultReason::emcy, FaultCode::device_error, i, h.last_emcy);
  }
  if (rebooted_[i]) return failure(FaultReason::node_rebooted, FaultCode::device_lost, i);
  if (h.heartbeat_lost) {
    // A drive that went silent altogether faults first for its TPDOs (they come every cycle);
    // once its heartbeat is overdue too, the fault says what is known now: the node is gone.
    if (operating_state().state == OperatingStateValue::fault && reason_ == FaultReason::feedback_stale &&
        device_status().fault.source_name() == j.name) {
      reason_ = FaultReason::heartbeat_lost;
      update_fault(Outcome::failed(FaultCode::device_lost, to_string(reason_), j.name, 0, h.silent_for));
      return Outcome::done();
    }
    return failure(FaultReason::heartbeat_lost, FaultCode::device_lost, i, 0, h.silent_for);
  }
  const TimeNs age = t - (f.valid ? f.last_received : start_time_);
  if (age > config_.feedback_timeout)
    return failure(FaultReason::feedback_stale, FaultCode::input_stale, i, 0, age);
  // A drive in fault while no reset is under way (an enable resets it, and has its own timeout).
  const bool drive_fault = f.state == cia402::State::fault || f.state == cia402::State::fault_reaction_active;
  if (drive_fault && !enabling())
    return failure(FaultReason::drive_fault, FaultCode::device_error, i, h.last_emcy);
  const OperatingStateValue st = operating_state().state;
  const bool powered = enabling() || st == OperatingStateValue::enabled || st == OperatingStateValue::paused;
  if (!powered || !f.valid) return Outcome::done();
  if (q_[i] < j.min || q_[i] > j.max) return failure(FaultReason::joint_limit, FaultCode::limit_exceeded, i);
  // The position read now answers the target sent one SYNC before.
  if (config_.mode == cia402::csp && j.following_error > 0 && following() &&
      std::abs(master_->setpoint(i) + j.offset - q_[i]) > j.following_error)
    return failure(FaultReason::following_error, FaultCode::limit_exceeded, i);
  return Outcome::done();
}

Outcome CanopenArm::check_health() noexcept {
  const can::BusState bus = bus_.state();
  status_.bus_state = static_cast<std::uint8_t>(bus);
  if (bus == can::BusState::bus_off || bus == can::BusState::down)
    return failure(FaultReason::bus_off, FaultCode::device_lost, n_, static_cast<std::uint32_t>(bus));
  for (std::size_t i = 0; i < n_; ++i)
    if (const Outcome o = check_axis(i); o.is_failed()) return o;
  return Outcome::done();
}

void CanopenArm::send_setpoints(const Setpoint& s) noexcept {
  const bool drive = following() && s.mode != ServoMode::none;
  for (std::size_t i = 0; i < n_; ++i) {
    double sp = 0;
    if (config_.mode == cia402::csp) {
      // Not following: the target tracks the drive, so that enabling never jumps; following
      // without a fresh command: the last target is held.
      sp = !following() ? q_[i] : drive ? s.joints[i] : target_[i];
    } else {
      sp = drive ? s.joints[i] : 0.0;
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
  const DeviceStatus& d = device_status();
  status_.state = operating_state().state;
  status_.reason = reason_;
  status_.faults = d.faults;
  if (d.faults != 0) status_.fault = d.fault;
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
  status_.watchdog_trips = watchdog_trips();
  status_.refused = d.refused;
}

}  // namespace saw::canopen
