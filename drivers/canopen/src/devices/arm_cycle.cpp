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
    case FaultReason::mode_mismatch:
      return "mode of operation not shown";
    case FaultReason::nmt_left:
      return "left NMT operational";
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
  if (start_time_ < 0) {
    start_time_ = t;
    // From now on the bus task carries this component's frames (its start-up used the bus).
    if (link_.shared()) link_.port->set_cycling(true);
  }
  master_->receive(t);
  read_feedback();
  return check_health();
}

// Nothing is decided on a statusword not yet received (0 reads as "not ready to switch on"):
// every drive's TPDOs first. Then fault resets (a bounded number of edges) and switched on;
// operation enabled only once every drive shows the mode asked for in 0x6061.
Outcome CanopenArm::enable() {
  const TimeNs t = now();
  if (const Outcome o = reconfigure_rebooted(); !o.is_done()) return o;
  for (std::size_t i = 0; i < n_; ++i)
    if (!master_->feedback(i).valid) return Outcome::pending();
  if (!enable_sent_) {
    reason_ = FaultReason::none;
    for (std::size_t i = 0; i < n_; ++i) {
      master_->request_fault_reset(i, t);
      emcy_pending_[i] = false;  // an EMCY before the reset is about the fault being reset
    }
    target_all(cia402::Target::switched_on);
    enable_sent_ = true;
    operation_sent_ = false;
    mode_wait_ = -1;
    return Outcome::pending();
  }
  bool switched_on = true, modes = true;
  for (std::size_t i = 0; i < n_; ++i) {
    if (const Outcome o = check_enabling(i); o.is_failed()) return o;
    const AxisFeedback& f = master_->feedback(i);
    switched_on = switched_on && master_->control(i).progress == cia402::Progress::reached;
    modes = modes && (!f.has_mode_display || f.mode_display == static_cast<std::int8_t>(config_.mode));
  }
  if (!operation_sent_) {
    if (!switched_on) return Outcome::pending();
    if (!modes) {
      if (mode_wait_ < 0) mode_wait_ = t;
      if (t - mode_wait_ <= config_.transition_timeout) return Outcome::pending();
      for (std::size_t i = 0; i < n_; ++i) {
        const AxisFeedback& f = master_->feedback(i);
        if (!f.has_mode_display || f.mode_display == static_cast<std::int8_t>(config_.mode)) continue;
        saw::log(LogLevel::error, name().c_str(),
                 "{} (node {}): 0x6061 shows mode {}, 0x6060 asked for mode {} ({}): not enabled",
                 config_.joints[i].name.c_str(), unsigned{config_.joints[i].node}, int{f.mode_display},
                 static_cast<int>(config_.mode), cia402::to_string(config_.mode).data());
        const auto detail = static_cast<std::uint32_t>(static_cast<std::uint8_t>(config_.mode)) << 8 |
                            static_cast<std::uint8_t>(f.mode_display);
        return failure(FaultReason::mode_mismatch, FaultCode::device_error, i, detail);
      }
    }
    target_all(cia402::Target::operation_enabled);
    operation_sent_ = true;
    return Outcome::pending();
  }
  for (std::size_t i = 0; i < n_; ++i)
    if (master_->feedback(i).state != cia402::State::operation_enabled) return Outcome::pending();
  enable_sent_ = operation_sent_ = false;
  return Outcome::done();
}

// A drive that rebooted lost its PDO maps, heartbeat and mode: the enable runs its configuration
// again (the start-up's writes, NMT start) before anything else.
Outcome CanopenArm::reconfigure_rebooted() noexcept {
  bool busy = false;
  for (std::size_t i = 0; i < n_; ++i) {
    switch (monitor_->reconfigure(*master_, i, now())) {
      case NodeMonitor::Step::busy:
        busy = true;
        break;
      case NodeMonitor::Step::failed:
        return failure(FaultReason::node_rebooted, FaultCode::device_lost, i,
                       static_cast<std::uint32_t>(master_->reconfiguration(i).abort));
      case NodeMonitor::Step::not_rebooted:
      case NodeMonitor::Step::done:
        break;
    }
  }
  return busy ? Outcome::pending() : Outcome::done();
}

// One drive during an enable: a fault its resets did not clear, or a transition that never came.
Outcome CanopenArm::check_enabling(std::size_t i) noexcept {
  const cia402::ControllerOutput& c = master_->control(i);
  const JointConfig& j = config_.joints[i];
  if (c.progress == cia402::Progress::fault) {
    const std::uint16_t code = error_code(i);
    saw::log(LogLevel::error, name().c_str(),
             "{} (node {}) stays in fault after {} fault resets: error code {:x} ({})", j.name.c_str(),
             unsigned{j.node}, c.fault_resets, unsigned{code}, emcy_name(code).data());
    return failure(FaultReason::drive_fault, FaultCode::device_error, i, code);
  }
  if (c.progress == cia402::Progress::timeout) {
    saw::log(LogLevel::error, name().c_str(), "{} (node {}) stuck in {} for {} ms: not enabled",
             j.name.c_str(), unsigned{j.node}, cia402::to_string(c.state).data(), c.in_state_for / 1'000'000);
    return failure(FaultReason::enable_timeout, FaultCode::device_error, i, master_->feedback(i).statusword);
  }
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
  if (operating_state().state != OperatingStateValue::fault) {
    reason_ = reason;
    status_.fault_node = axis < n_ ? config_.joints[axis].node : 0;
  }
  const std::string_view source =
      axis < n_ ? std::string_view(config_.joints[axis].name) : std::string_view("bus");
  return Outcome::failed(code, to_string(reason), source, detail, age);
}

bool CanopenArm::says() const noexcept { return operating_state().state != OperatingStateValue::fault; }

// 0x603F when a TPDO maps it and it says something, else the newest EMCY's code.
std::uint16_t CanopenArm::error_code(std::size_t i) const noexcept {
  const AxisFeedback& f = master_->feedback(i);
  return f.has_error_code && f.error_code != 0 ? f.error_code : master_->health(i).last_emcy;
}

// An EMCY is an error when the drive's statusword shows fault (CiA 402: a drive that faults
// says so there) and a warning when the drive's next TPDOs do not: a temperature warning, a CAN
// error-passive or overrun of a drive that goes on operating is logged and shown, not a FAULT.
Outcome CanopenArm::check_emcy(std::size_t i, bool drive_fault) noexcept {
  const AxisHealth& h = master_->health(i);
  const AxisFeedback& f = master_->feedback(i);
  const JointConfig& j = config_.joints[i];
  if (h.emcy_count != emcy_seen_[i]) {
    emcy_seen_[i] = h.emcy_count;
    emcy_pending_[i] = true;
    emcy_tpdos_[i] = 0;
  }
  if (!emcy_pending_[i] || enabling()) return Outcome::done();  // an enable resets faults
  // An RPDO timeout says this master's RPDOs stopped reaching the drive (a starved cycle), and
  // that the drive already did what 0x6007 says whatever its statusword shows: a fault at once.
  if (drive_fault || h.last_emcy == emcy_code::rpdo_timeout) {
    emcy_pending_[i] = false;
    if (says())
      saw::log(LogLevel::error, name().c_str(),
               "{} (node {}): EMCY {:x} ({}), error register {:x}, the drive in {}", j.name.c_str(),
               unsigned{j.node}, unsigned{h.last_emcy}, emcy_name(h.last_emcy).data(),
               unsigned{h.error_register}, cia402::to_string(f.state).data());
    return failure(FaultReason::emcy, FaultCode::device_error, i, h.last_emcy);
  }
  // The statusword of the SYNC after the EMCY, and one more: a drive's fault may lag its EMCY.
  constexpr int settle_tpdos = 3;
  if (f.fresh && ++emcy_tpdos_[i] >= settle_tpdos) {
    emcy_pending_[i] = false;
    ++status_.warnings;
    status_.last_warning = h.last_emcy;
    status_.last_warning_register = h.error_register;
    status_.last_warning_node = j.node;
    saw::log(LogLevel::warning, name().c_str(),
             "{} (node {}): EMCY {:x} ({}), error register {:x}: a warning, the drive stays {}",
             j.name.c_str(), unsigned{j.node}, unsigned{h.last_emcy}, emcy_name(h.last_emcy).data(),
             unsigned{h.error_register}, cia402::to_string(f.state).data());
  }
  return Outcome::done();
}

Outcome CanopenArm::check_axis(std::size_t i) noexcept {
  const AxisHealth& h = master_->health(i);
  const AxisFeedback& f = master_->feedback(i);
  const JointConfig& j = config_.joints[i];
  const TimeNs t = now();
  monitor_->look(i, enabling());  // a boot-up: its PDOs and mode are gone, the next enable configures it
  const bool drive_fault = f.state == cia402::State::fault || f.state == cia402::State::fault_reaction_active;
  if (const Outcome o = check_emcy(i, drive_fault); o.is_failed()) return o;
  if (monitor_->rebooted(i)) {
    if (enabling()) return Outcome::done();  // the enable configures it again (its checks after)
    if (says()) monitor_->say_rebooted(i);
    return failure(FaultReason::node_rebooted, FaultCode::device_lost, i);
  }
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
  // A drive that leaves operational (its own error behaviour, another master's NMT command) no
  // longer takes PDOs: that drive's fault at once, not a stale feedback 100 ms later.
  if (monitor_->left_operational(i, says()))
    return failure(FaultReason::nmt_left, FaultCode::device_lost, i, static_cast<std::uint32_t>(h.nmt_state));
  const TimeNs age = t - (f.valid ? f.last_received : std::max(start_time_, f.watch_from));
  if (age > config_.feedback_timeout)
    return failure(FaultReason::feedback_stale, FaultCode::input_stale, i, 0, age);
  // A drive in fault while no reset is under way (an enable resets it, and has its own timeout).
  if (drive_fault && !enabling()) {
    if (says())
      saw::log(LogLevel::error, name().c_str(), "{} (node {}) in fault: error code {:x} ({})", j.name.c_str(),
               unsigned{j.node}, unsigned{error_code(i)}, emcy_name(error_code(i)).data());
    return failure(FaultReason::drive_fault, FaultCode::device_error, i, error_code(i));
  }
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
  // The last fault's reason stays with the last fault (an enable clears reason_).
  if (reason_ != FaultReason::none) status_.reason = reason_;
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
}

}  // namespace saw::canopen
